// The synthesized ladder climb (synthesize.hpp): one limb at a time, hands on the rails, feet on
// the rungs, every hold exact; the root rises while a foot swings; legs and arms by two-link IK.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "kg/motion/kinematics.hpp"
#include "kg/synth/synthesize.hpp"
#include "synth_detail.hpp"

namespace kg::synth {

using namespace detail;

namespace {

Side other(Side side) {
  return side == kLeft ? kRight : kLeft;
}

// Smoothstep 3x^2 - 2x^3 on [0, 1] (clamped): zero slope at both ends, so pieces joined at
// their ends are C1.
double smooth(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// One limb's moves, in time order: it leaves `from` (a rung index for a foot, a grip level for
// a hand) at t0 and holds at `to` from t1.
struct Move {
  double t0 = 0, t1 = 0;
  int from = 0, to = 0;
};

// Where a foot's hold point (the sole under the ball) is during its moves; between moves it
// holds. The path of a move leaves the rung backwards, rises behind the rungs and comes down onto
// the new rung from above (see the header comment of synthesize.hpp).
class FootPath {
 public:
  FootPath(std::vector<Move> moves, Eigen::Vector3d base, double spacing, double back, double clear)
      : moves_(std::move(moves)), base_(std::move(base)), spacing_(spacing), back_(back), clear_(clear) {}

  Eigen::Vector3d at(double t) const {
    int rung = moves_.empty() ? 1 : moves_.front().from;
    for (const Move& m : moves_) {
      if (t <= m.t0) break;
      if (t >= m.t1) {
        rung = m.to;
        continue;
      }
      const double u = (t - m.t0) / (m.t1 - m.t0);
      const double ya = m.from * spacing_, yb = m.to * spacing_;
      // Up to the new rung's top plus `clear` by u = 0.8, then down onto it; back from the
      // ladder by u = 0.3, forward again from u = 0.7. Every piece starts and ends at rest.
      const double y =
          u <= 0.8 ? ya + (yb + clear_ - ya) * smooth(u / 0.8) : yb + clear_ * (1 - smooth((u - 0.8) / 0.2));
      const double pulled = u <= 0.3 ? smooth(u / 0.3) : u < 0.7 ? 1.0 : 1 - smooth((u - 0.7) / 0.3);
      return {base_.x(), y, base_.z() - back_ * pulled};
    }
    return {base_.x(), rung * spacing_, base_.z()};
  }

 private:
  std::vector<Move> moves_;
  Eigen::Vector3d base_;  // x and z of the hold point on any rung
  double spacing_, back_, clear_;
};

// Where a hand's grip point is: on its rail at grip_base + (level - 1) * spacing while it holds,
// drawn back from the rail while it reaches up.
class HandPath {
 public:
  HandPath(std::vector<Move> moves, Eigen::Vector3d base, double spacing, double back)
      : moves_(std::move(moves)), base_(std::move(base)), spacing_(spacing), back_(back) {}

  Eigen::Vector3d at(double t, double grip_base) const {
    int level = moves_.empty() ? 1 : moves_.front().from;
    for (const Move& m : moves_) {
      if (t <= m.t0) break;
      if (t >= m.t1) {
        level = m.to;
        continue;
      }
      const double u = (t - m.t0) / (m.t1 - m.t0);
      const double ya = grip_base + (m.from - 1) * spacing_, yb = grip_base + (m.to - 1) * spacing_;
      const double rise = u * u * u * (10 - 15 * u + 6 * u * u);  // quintic smoothstep
      return {base_.x(), ya + (yb - ya) * rise, base_.z() - back_ * 16 * u * u * (1 - u) * (1 - u)};
    }
    return {base_.x(), grip_base + (level - 1) * spacing_, base_.z()};
  }

 private:
  std::vector<Move> moves_;
  Eigen::Vector3d base_;
  double spacing_, back_;
};

std::string figure_text(double stature) {
  std::ostringstream s;
  s << "a figure of stature " << stature << " m";
  return s.str();
}

}  // namespace

void ClimbOptions::validate() const {
  const ClimbOptions& options = *this;
  check_range("climb", "rungs", options.rungs, kClimbRungsRange.min, kClimbRungsRange.max, "");
  check_range("climb", "rung_spacing", options.rung_spacing, kRungSpacingRange.min, kRungSpacingRange.max,
              "m");
  check_range("climb", "rail_half_width", options.rail_half_width, kRailHalfWidthRange.min,
              kRailHalfWidthRange.max, "m");
  check_range("climb", "ladder_distance", options.ladder_distance, kLadderDistanceRange.min,
              kLadderDistanceRange.max, "m");
  check_range("climb", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("climb", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");
}

namespace {

// Timeline: stand on rung 1, then per rung climbed a hand move followed by a foot move of the
// other side (the right foot first), and one more pair bringing the trailing hand and foot
// level with the leading ones; stand again.
constexpr double kStart = 0.5, kHandTime = 0.55, kFootTime = 0.8, kPause = 0.1, kRest = 0.6;

Side foot_side(int move) {
  return move % 2 == 1 ? kRight : kLeft;
}
int from_level(int move) {
  return std::max(move - 1, 1);
}
int to_level(int move, int rungs) {
  return std::min(move + 1, rungs + 1);
}

struct ClimbTimeline {
  int rungs = 0, moves = 0;
  std::vector<double> hand_t0{}, foot_t0{};  // when move m (1 ... moves) of a hand, of a foot starts
  double end = 0;
};

ClimbTimeline plan_timeline(int rungs) {
  ClimbTimeline tl{.rungs = rungs, .moves = rungs + 1};
  tl.hand_t0.resize(static_cast<std::size_t>(tl.moves) + 1);
  tl.foot_t0.resize(tl.hand_t0.size());
  double t = kStart;
  for (int m = 1; m <= tl.moves; ++m) {
    tl.hand_t0[static_cast<std::size_t>(m)] = t;
    tl.foot_t0[static_cast<std::size_t>(m)] = t + kHandTime + kPause;
    t = tl.foot_t0[static_cast<std::size_t>(m)] + kFootTime + kPause;
  }
  tl.end = t - kPause + kRest;
  return tl;
}

struct LimbPaths {
  std::array<std::vector<Move>, 2> foot_moves, hand_moves;
  std::array<FootPath, 2> feet;
  std::array<HandPath, 2> hands;
};

// Limb paths. The feet stand a little inside the rails; the hands grip the rails.
LimbPaths limb_paths(const ClimbOptions& options, double H, const ClimbTimeline& tl) {
  const double s = options.rung_spacing, w = options.rail_half_width, D = options.ladder_distance;
  const double foot_x = 0.45 * w;
  const double foot_back = 0.1 * H + 0.02;  // clears the toes (0.043 H ahead) behind a rung
  const double foot_clear = 0.025 * H;      // above the rung top before coming down onto it
  const double hand_back = 0.035 * H;
  std::array<std::vector<Move>, 2> foot_moves, hand_moves;
  for (int m = 1; m <= tl.moves; ++m) {
    const double ht = tl.hand_t0[static_cast<std::size_t>(m)], ft = tl.foot_t0[static_cast<std::size_t>(m)];
    hand_moves[other(foot_side(m))].push_back({ht, ht + kHandTime, from_level(m), to_level(m, tl.rungs)});
    foot_moves[foot_side(m)].push_back({ft, ft + kFootTime, from_level(m), to_level(m, tl.rungs)});
  }
  return {foot_moves,
          hand_moves,
          {FootPath(foot_moves[kLeft], {foot_x, 0, D}, s, foot_back, foot_clear),
           FootPath(foot_moves[kRight], {-foot_x, 0, D}, s, foot_back, foot_clear)},
          {HandPath(hand_moves[kLeft], {w, 0, D}, s, hand_back),
           HandPath(hand_moves[kRight], {-w, 0, D}, s, hand_back)}};
}

// The feet keep their world orientation (flat, straight ahead) all through, so a foot's hold
// point stays put and the ankle with it. A hand turns about its grip point (which stays put)
// with the arm: its fingers point halfway between the shoulder-to-grip line and the forearm,
// in the arm's plane, so the wrist only flexes (a fixed hand would twist it through 100
// degrees as the body rises past the grip).
struct HoldPoints {
  Eigen::Vector3d sole_local;  // on toe[]: under the ball
  Eigen::Vector3d sole_from_ankle;
  double grip_depth = 0;
  Eigen::Vector3d grip_local;  // on hand[]: the middle of the grip
};

HoldPoints hold_points(const Figure& fig) {
  HoldPoints h;
  h.sole_local = Eigen::Vector3d(0, -fig.dims.ball_height, 0);
  h.sole_from_ankle = FootGeometry(fig).ball_offset() + h.sole_local;
  h.grip_depth = 0.45 * fig.dims.hand;
  h.grip_local = Eigen::Vector3d(0, -h.grip_depth, 0);
  return h;
}

// The mean height of the rungs the feet stand on; the root rises with it while a foot swings
// (a quintic from rest to rest), and keeps above it by `lift` (fit_lift).
Curve feet_mean_curve(const ClimbTimeline& tl, double spacing) {
  Curve feet_mean;
  double level = spacing;
  double t_prev = 0;
  for (int m = 1; m <= tl.moves; ++m) {
    const double ft = tl.foot_t0[static_cast<std::size_t>(m)];
    feet_mean.add_hold(t_prev, ft, level);
    const double next = level + (to_level(m, tl.rungs) - from_level(m)) * spacing / 2;
    feet_mean.add_quintic(ft, ft + kFootTime, level, 0, 0, next, 0, 0);
    level = next;
    t_prev = ft + kFootTime;
  }
  feet_mean.add_hold(t_prev, tl.end, level);
  return feet_mean;
}

struct Sway {
  Curve x, roll;
};

// Sideways, the pelvis shifts over the standing foot while the other swings and hikes the
// swinging side.
Sway sway_curves(const ClimbTimeline& tl, double H) {
  const double sway = 0.012 * H, hike = 0.04;
  std::vector<std::pair<double, double>> kx{{kStart, 0}}, kroll{{kStart, 0}};
  for (int m = 1; m <= tl.moves; ++m) {
    const Side swing = foot_side(m);
    const double scale = (m == 1 || m == tl.moves) ? 0.5 : 1.0;
    const double mid = tl.foot_t0[static_cast<std::size_t>(m)] + kFootTime / 2;
    kx.push_back({mid, -side_sign(swing) * sway * scale});
    kroll.push_back({mid, side_sign(swing) * hike * scale});
    const double hand_mid =
        (m < tl.moves ? tl.hand_t0[static_cast<std::size_t>(m) + 1] : tl.end - kRest) + kHandTime / 2;
    kx.push_back({hand_mid, 0});
    kroll.push_back({hand_mid, 0});
  }
  return {monotone_curve(kx), monotone_curve(kroll)};
}

// The trunk leans towards the ladder, the head looks up. The pelvis tilts back (the spine takes
// the difference to the chest's lean) so that a thigh raised to step two rungs up stays near 75
// degrees of hip flexion: at 90 the hip's ZXY angles would meet gimbal lock and swing wildly from
// frame to frame.
constexpr double kPelvisPitch = -0.3, kChestLean = 0.2;

// Everything a pose of the climb comes from but the root's lift and the grips' height.
struct Climb {
  const ClimbOptions& options;
  const Figure& fig;
  const PoseWriter& writer;
  ClimbTimeline timeline;
  LimbPaths limbs;
  HoldPoints points;
  Curve feet_mean;
  Sway sway;
};

Climb plan_climb(const ClimbOptions& options, const Figure& fig, const PoseWriter& writer) {
  ClimbTimeline timeline = plan_timeline(options.rungs);
  LimbPaths limbs = limb_paths(options, fig.dims.stature, timeline);
  Curve feet_mean = feet_mean_curve(timeline, options.rung_spacing);
  Sway sway = sway_curves(timeline, fig.dims.stature);
  return {options,
          fig,
          writer,
          std::move(timeline),
          std::move(limbs),
          hold_points(fig),
          std::move(feet_mean),
          std::move(sway)};
}

HandTarget hand_on_grip(const Climb& c, const BodyPose& p, Side side, const Eigen::Vector3d& grip) {
  const FigureDimensions& dims = c.fig.dims;
  const double grip_depth = c.points.grip_depth;
  HandTarget h;
  h.elbow_pole = p.chest * Eigen::Vector3d(side_sign(side) * 0.6, -0.7, -0.4);  // down, out, back
  const Eigen::Vector3d shoulder = c.writer.shoulder_world(p, side);
  const Eigen::Vector3d line = (grip - shoulder).normalized();
  const Eigen::Vector3d elbow = two_link_middle(shoulder, grip - grip_depth * line, dims.upper_arm,
                                                dims.forearm, h.elbow_pole, PoseWriter::kMaxExtension);
  const Eigen::Vector3d forearm = (grip - grip_depth * line - elbow).normalized();
  const Eigen::Vector3d across = line.cross(h.elbow_pole).normalized();  // the elbow's hinge axis
  Eigen::Vector3d fingers = line + forearm;
  fingers = (fingers - fingers.dot(across) * across).normalized();
  h.hand.col(0) = across;
  h.hand.col(1) = -fingers;  // the hand's bone runs along its -Y
  h.hand.col(2) = across.cross(-fingers);
  h.wrist = grip - h.hand * c.points.grip_local;
  return h;
}

BodyPose pose_at(const Climb& c, double time, double lift, double grip_base) {
  BodyPose p;
  p.root = Eigen::Vector3d(c.sway.x.value(time), c.feet_mean.value(time) + lift, 0);
  const double r = c.sway.roll.value(time);
  p.pelvis = rot_z(r) * rot_x(kPelvisPitch);
  p.chest = rot_z(-0.5 * r) * rot_x(kChestLean);
  p.head = rot_x(-0.15);
  for (Side side : {kLeft, kRight}) {
    p.feet[side].ankle = c.limbs.feet[side].at(time) - c.points.sole_from_ankle;
    p.hands[side] = hand_on_grip(c, p, side, c.limbs.hands[side].at(time, grip_base));
  }
  return p;
}

// Sampled at a fixed rate, not at `fps`, so every frame rate gets the same climb.
constexpr double kSearchRate = 120;

// The least and the largest extension of either limb of a pair (legs or arms) over the climb.
std::pair<double, double> extension_range(const Climb& c, double lift, double grip_base,
                                          double (PoseWriter::*extension)(const BodyPose&, Side) const) {
  const double end = c.timeline.end;
  const int samples = static_cast<int>(std::ceil(end * kSearchRate)) + 1;
  std::pair<double, double> r{1e9, 0};
  for (int i = 0; i < samples; ++i) {
    const BodyPose p = pose_at(c, std::min(i / kSearchRate, end), lift, grip_base);
    for (Side side : {kLeft, kRight}) {
      const double e = (c.writer.*extension)(p, side);
      r = {std::min(r.first, e), std::max(r.second, e)};
    }
  }
  return r;
}

// The root as high above the feet as lets the most stretched leg reach 0.93 of its length.
double fit_lift(const Climb& c) {
  const ClimbOptions& o = c.options;
  const double H = c.fig.dims.stature;
  auto leg_range = [&](double lift) { return extension_range(c, lift, 0, &PoseWriter::leg_extension); };
  const double leg_reach = 0.93;
  double lo = 0, hi = 1.2 * c.fig.dims.leg_length();
  if (leg_range(lo).second > leg_reach) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << o.ladder_distance << " m is too far for the legs of "
        << figure_text(H) << " to reach the rungs";
    throw std::invalid_argument(msg.str());
  }
  for (int i = 0; i < 50; ++i) {
    const double mid = (lo + hi) / 2;
    (leg_range(mid).second <= leg_reach ? lo : hi) = mid;
  }
  const double lift = lo;
  const double leg_min = leg_range(lift).first;
  // The most bent leg: the foot stepping onto a rung a rung_spacing above the other. Below 0.35
  // of the leg's length (hip to ankle) the knee folds past about 140 degrees.
  if (leg_min < 0.35) {
    std::ostringstream msg;
    msg << "synthesize_climb: rung_spacing " << o.rung_spacing << " m is too large for " << figure_text(H)
        << ": stepping up two rungs would fold its knees shut (the most bent leg spans " << leg_min
        << " of its length, under 0.35)";
    throw std::invalid_argument(msg.str());
  }
  return lift;
}

void check_arm_reach(const Climb& c, const std::pair<double, double>& arm_range) {
  const ClimbOptions& o = c.options;
  const auto [arm_min, arm_max] = arm_range;
  if (arm_max > 0.92) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << o.ladder_distance << " m is too far for the arms of "
        << figure_text(c.fig.dims.stature) << " to hold the rails (rung_spacing " << o.rung_spacing << " m)";
    throw std::invalid_argument(msg.str());
  }
  // Elbows folded past about 145 degrees (the shoulder to wrist distance under 0.3 of the arm's
  // length): the ladder is too close for this figure.
  if (arm_min < 0.3) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << o.ladder_distance << " m is too close for the arms of "
        << figure_text(c.fig.dims.stature) << ": its elbows would fold shut (rung_spacing " << o.rung_spacing
        << " m)";
    throw std::invalid_argument(msg.str());
  }
}

// The grips at the height that stretches the arms least: over a hold a grip passes from high
// above the shoulder (just grabbed) to below it (about to let go), so the most stretched arm is
// the least when the grips straddle the shoulders. Its extension falls, then rises with the
// grip height: a golden-section search finds the least.
double fit_grip_height(const Climb& climb, double lift) {
  auto arm_range = [&](double grip_base) {
    return extension_range(climb, lift, grip_base, &PoseWriter::arm_extension);
  };
  const double H = climb.fig.dims.stature;
  const double shoulder_y = climb.writer.shoulder_world(pose_at(climb, 0, lift, 0), kLeft).y();
  double a = shoulder_y - 0.3 * H, b = shoulder_y + 0.3 * H;
  const double golden = (std::sqrt(5.0) - 1) / 2;
  double c = b - golden * (b - a), d = a + golden * (b - a);
  double fc = arm_range(c).second, fd = arm_range(d).second;
  for (int i = 0; i < 40; ++i) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - golden * (b - a);
      fc = arm_range(c).second;
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + golden * (b - a);
      fd = arm_range(d).second;
    }
  }
  const double grip_base = (a + b) / 2;
  check_arm_reach(climb, arm_range(grip_base));
  return grip_base;
}

constexpr double kRungRadius = 0.016;

// A knee stepping up comes forward; it must stay behind the rungs (the ladder is not built with
// gaps for knees).
void check_knee_clearance(const Climb& c, const motion::Motion& motion, int frames) {
  const Figure& fig = c.fig;
  double knee_forward = -1e9;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(fig.skeleton->joint_count()));
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(*fig.skeleton, motion.values.row(f), world);
    for (Side side : {kLeft, kRight})
      knee_forward = std::max(knee_forward, world[static_cast<std::size_t>(fig.leg[side])].translation().z());
  }
  if (knee_forward > c.options.ladder_distance - kRungRadius) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << c.options.ladder_distance << " m is too close for "
        << figure_text(fig.dims.stature) << ": its knees would pass through the ladder (a knee comes "
        << knee_forward << " m forward)";
    throw std::invalid_argument(msg.str());
  }
}

Ladder build_ladder(const ClimbOptions& options, double grip_base) {
  const double s = options.rung_spacing;
  Ladder ladder;
  ladder.rung_spacing = s;
  ladder.rail_half_width = options.rail_half_width;
  ladder.distance = options.ladder_distance;
  ladder.rung_radius = kRungRadius;
  // Rungs up to 10 cm above the highest grip, the rails half a spacing above the top rung.
  ladder.rung_count = static_cast<int>(std::ceil((grip_base + options.rungs * s + 0.1) / s));
  ladder.rail_top = (ladder.rung_count + 0.5) * s;
  return ladder;
}

// The holds: each limb holds from the end of one move to the start of its next.
void record_holds(const Climb& c, double grip_base, const Ladder& ladder, int frames,
                  std::vector<Hold>& holds) {
  const double fps = c.options.fps;
  const double t_end = (frames - 1) / fps;
  auto add_hold = [&](Side side, bool hand, int level, double t0, double t1) {
    Hold h;
    h.side = side;
    h.hand = hand;
    h.rung = hand ? 0 : level;
    h.joint = hand ? c.fig.hand[side] : c.fig.toe[side];
    h.local = hand ? c.points.grip_local : c.points.sole_local;
    std::tie(h.first_frame, h.last_frame) = frame_span(t0, std::min(t1, t_end), fps);
    h.world = hand ? c.limbs.hands[side].at(t0, grip_base) : c.limbs.feet[side].at(t0);
    h.segment_a = hand ? ladder.rail_a(side) : ladder.rung_a(level);
    h.segment_b = hand ? ladder.rail_b(side) : ladder.rung_b(level);
    if (h.first_frame <= h.last_frame) holds.push_back(h);
  };
  for (bool hand : {true, false}) {
    for (Side side : {kLeft, kRight}) {
      const std::vector<Move>& ms = hand ? c.limbs.hand_moves[side] : c.limbs.foot_moves[side];
      double t0 = 0;
      int level = 1;
      for (const Move& m : ms) {
        add_hold(side, hand, level, t0, m.t0);
        t0 = m.t1;
        level = m.to;
      }
      add_hold(side, hand, level, t0, t_end);
    }
  }
}

}  // namespace

std::string Hold::name() const {
  std::string n = std::string(side_name(side)) + (hand ? "Hand" : "Foot");
  if (hand) {
    char height[32];
    std::snprintf(height, sizeof height, "%.2f", world.y());
    return n + " on the " + (side == kLeft ? "left" : "right") + " rail at " + height + " m";
  }
  return n + " on rung " + std::to_string(rung);
}

Synthesis synthesize_climb(const ClimbOptions& options) {
  options.validate();
  Synthesis out;
  out.figure = make_figure(options.stature);
  PoseWriter writer(out.figure);
  const Climb climb = plan_climb(options, out.figure, writer);
  const double lift = fit_lift(climb);
  const double grip_base = fit_grip_height(climb, lift);

  const int frames = static_cast<int>(std::lround(climb.timeline.end * options.fps)) + 1;
  out.max_leg_extension = write_frames(
      writer, out.figure, [&](double time) { return pose_at(climb, time, lift, grip_base); }, frames,
      options.fps, "synth_climb", out.motion);
  for (int f = 0; f < frames; ++f) {
    const BodyPose p = pose_at(climb, f / options.fps, lift, grip_base);
    for (Side side : {kLeft, kRight})
      out.max_arm_extension = std::max(out.max_arm_extension, writer.arm_extension(p, side));
  }
  if (out.max_leg_extension >= PoseWriter::kMaxExtension ||
      out.max_arm_extension >= PoseWriter::kMaxExtension)
    throw std::logic_error("synthesize_climb: a limb cannot reach its hold");
  check_knee_clearance(climb, out.motion, frames);

  out.ladder = build_ladder(options, grip_base);
  record_holds(climb, grip_base, out.ladder, frames, out.holds);
  out.steps = options.rungs;
  return out;
}

}  // namespace kg::synth
