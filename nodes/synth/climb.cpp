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
  check_range("climb", "rungs", options.rungs, kClimbRungsRange.min, kClimbRungsRange.max, "");
  check_range("climb", "rung_spacing", options.rung_spacing, kRungSpacingRange.min, kRungSpacingRange.max,
              "m");
  check_range("climb", "rail_half_width", options.rail_half_width, kRailHalfWidthRange.min,
              kRailHalfWidthRange.max, "m");
  check_range("climb", "ladder_distance", options.ladder_distance, kLadderDistanceRange.min,
              kLadderDistanceRange.max, "m");
  check_range("climb", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("climb", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");

  Synthesis out;
  out.figure = make_figure(options.stature);
  const Figure& fig = out.figure;
  const FigureDimensions& dims = fig.dims;
  const double H = dims.stature;
  const FootGeometry geo(fig);
  PoseWriter writer(fig);

  const int n = options.rungs;
  const double s = options.rung_spacing, w = options.rail_half_width, D = options.ladder_distance;

  // Timeline: stand on rung 1, then per rung climbed a hand move followed by a foot move of the
  // other side (the right foot first), and one more pair bringing the trailing hand and foot
  // level with the leading ones; stand again.
  const double t_start = 0.5, hand_time = 0.55, foot_time = 0.8, pause = 0.1, t_rest = 0.6;
  const int moves = n + 1;
  auto foot_side = [](int m) { return m % 2 == 1 ? kRight : kLeft; };
  auto from_level = [](int m) { return std::max(m - 1, 1); };
  auto to_level = [n](int m) { return std::min(m + 1, n + 1); };
  std::vector<double> hand_t0(static_cast<std::size_t>(moves) + 1), foot_t0(hand_t0.size());
  double t = t_start;
  for (int m = 1; m <= moves; ++m) {
    hand_t0[static_cast<std::size_t>(m)] = t;
    foot_t0[static_cast<std::size_t>(m)] = t + hand_time + pause;
    t = foot_t0[static_cast<std::size_t>(m)] + foot_time + pause;
  }
  const double end = t - pause + t_rest;

  // Limb paths. The feet stand a little inside the rails; the hands grip the rails.
  const double foot_x = 0.45 * w;
  const double foot_back = 0.1 * H + 0.02;  // clears the toes (0.043 H ahead) behind a rung
  const double foot_clear = 0.025 * H;      // above the rung top before coming down onto it
  const double hand_back = 0.035 * H;
  std::array<std::vector<Move>, 2> foot_moves, hand_moves;
  for (int m = 1; m <= moves; ++m) {
    const double ht = hand_t0[static_cast<std::size_t>(m)], ft = foot_t0[static_cast<std::size_t>(m)];
    hand_moves[other(foot_side(m))].push_back({ht, ht + hand_time, from_level(m), to_level(m)});
    foot_moves[foot_side(m)].push_back({ft, ft + foot_time, from_level(m), to_level(m)});
  }
  const std::array<FootPath, 2> feet{FootPath(foot_moves[kLeft], {foot_x, 0, D}, s, foot_back, foot_clear),
                                     FootPath(foot_moves[kRight], {-foot_x, 0, D}, s, foot_back, foot_clear)};
  const std::array<HandPath, 2> hands{HandPath(hand_moves[kLeft], {w, 0, D}, s, hand_back),
                                      HandPath(hand_moves[kRight], {-w, 0, D}, s, hand_back)};

  // The feet keep their world orientation (flat, straight ahead) all through, so a foot's hold
  // point stays put and the ankle with it. A hand turns about its grip point (which stays put)
  // with the arm: its fingers point halfway between the shoulder-to-grip line and the forearm,
  // in the arm's plane, so the wrist only flexes (a fixed hand would twist it through 100
  // degrees as the body rises past the grip).
  const Eigen::Vector3d sole_local(0, -dims.ball_height, 0);  // on toe[]: under the ball
  const Eigen::Vector3d sole_from_ankle = geo.ball_offset() + sole_local;
  const double grip_depth = 0.45 * dims.hand;
  const Eigen::Vector3d grip_local(0, -grip_depth, 0);  // on hand[]: the middle of the grip

  // The mean height of the rungs the feet stand on; the root rises with it while a foot swings
  // (a quintic from rest to rest), and keeps above it by `lift` (chosen below).
  Curve feet_mean;
  {
    double level = s;
    double t_prev = 0;
    for (int m = 1; m <= moves; ++m) {
      const double ft = foot_t0[static_cast<std::size_t>(m)];
      feet_mean.add_hold(t_prev, ft, level);
      const double next = level + (to_level(m) - from_level(m)) * s / 2;
      feet_mean.add_quintic(ft, ft + foot_time, level, 0, 0, next, 0, 0);
      level = next;
      t_prev = ft + foot_time;
    }
    feet_mean.add_hold(t_prev, end, level);
  }
  // Sideways, the pelvis shifts over the standing foot while the other swings and hikes the
  // swinging side; the trunk leans towards the ladder, the head looks up.
  const double sway = 0.012 * H, hike = 0.04;
  std::vector<std::pair<double, double>> kx{{t_start, 0}}, kroll{{t_start, 0}};
  for (int m = 1; m <= moves; ++m) {
    const Side swing = foot_side(m);
    const double scale = (m == 1 || m == moves) ? 0.5 : 1.0;
    const double mid = foot_t0[static_cast<std::size_t>(m)] + foot_time / 2;
    kx.push_back({mid, -side_sign(swing) * sway * scale});
    kroll.push_back({mid, side_sign(swing) * hike * scale});
    const double hand_mid =
        (m < moves ? hand_t0[static_cast<std::size_t>(m) + 1] : end - t_rest) + hand_time / 2;
    kx.push_back({hand_mid, 0});
    kroll.push_back({hand_mid, 0});
  }
  const Curve x_curve = monotone_curve(kx), roll = monotone_curve(kroll);
  // The pelvis tilts back (the spine takes the difference to the chest's lean) so that a thigh
  // raised to step two rungs up stays near 75 degrees of hip flexion: at 90 the hip's ZXY angles
  // would meet gimbal lock and swing wildly from frame to frame.
  const double pelvis_pitch = -0.3, chest_lean = 0.2;

  auto pose_at = [&](double time, double lift, double grip_base) {
    BodyPose p;
    p.root = Eigen::Vector3d(x_curve.value(time), feet_mean.value(time) + lift, 0);
    const double r = roll.value(time);
    p.pelvis = rot_z(r) * rot_x(pelvis_pitch);
    p.chest = rot_z(-0.5 * r) * rot_x(chest_lean);
    p.head = rot_x(-0.15);
    for (Side side : {kLeft, kRight}) {
      FootState& f = p.feet[side];
      f.ankle = feet[side].at(time) - sole_from_ankle;
      HandTarget h;
      h.elbow_pole = p.chest * Eigen::Vector3d(side_sign(side) * 0.6, -0.7, -0.4);  // down, out, back
      const Eigen::Vector3d grip = hands[side].at(time, grip_base);
      const Eigen::Vector3d shoulder = writer.shoulder_world(p, side);
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
      h.wrist = grip - h.hand * grip_local;
      p.hands[side] = h;
    }
    return p;
  };

  // Sampled at a fixed rate, not at `fps`, so every frame rate gets the same climb.
  const double search_rate = 120;
  const int samples = static_cast<int>(std::ceil(end * search_rate)) + 1;
  auto sample_time = [&](int i) { return std::min(i / search_rate, end); };
  auto leg_range = [&](double lift) {
    std::pair<double, double> r{1e9, 0};
    for (int i = 0; i < samples; ++i) {
      const BodyPose p = pose_at(sample_time(i), lift, 0);
      for (Side side : {kLeft, kRight}) {
        const double e = writer.leg_extension(p, side);
        r = {std::min(r.first, e), std::max(r.second, e)};
      }
    }
    return r;
  };
  // The root as high above the feet as lets the most stretched leg reach 0.93 of its length.
  const double leg_reach = 0.93;
  double lo = 0, hi = 1.2 * dims.leg_length();
  if (leg_range(lo).second > leg_reach) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << D << " m is too far for the legs of " << figure_text(H)
        << " to reach the rungs";
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
    msg << "synthesize_climb: rung_spacing " << s << " m is too large for " << figure_text(H)
        << ": stepping up two rungs would fold its knees shut (the most bent leg spans " << leg_min
        << " of its length, under 0.35)";
    throw std::invalid_argument(msg.str());
  }

  // The grips at the height that stretches the arms least: over a hold a grip passes from high
  // above the shoulder (just grabbed) to below it (about to let go), so the most stretched arm is
  // the least when the grips straddle the shoulders. Its extension falls, then rises with the
  // grip height: a golden-section search finds the least.
  auto arm_range = [&](double grip_base) {
    std::pair<double, double> r{1e9, 0};
    for (int i = 0; i < samples; ++i) {
      const BodyPose p = pose_at(sample_time(i), lift, grip_base);
      for (Side side : {kLeft, kRight}) {
        const double e = writer.arm_extension(p, side);
        r = {std::min(r.first, e), std::max(r.second, e)};
      }
    }
    return r;
  };
  const double shoulder_y = writer.shoulder_world(pose_at(0, lift, 0), kLeft).y();
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
  const auto [arm_min, arm_max] = arm_range(grip_base);
  if (arm_max > 0.92) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << D << " m is too far for the arms of " << figure_text(H)
        << " to hold the rails (rung_spacing " << s << " m)";
    throw std::invalid_argument(msg.str());
  }
  // Elbows folded past about 145 degrees (the shoulder to wrist distance under 0.3 of the arm's
  // length): the ladder is too close for this figure.
  if (arm_min < 0.3) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << D << " m is too close for the arms of " << figure_text(H)
        << ": its elbows would fold shut (rung_spacing " << s << " m)";
    throw std::invalid_argument(msg.str());
  }

  const int frames = static_cast<int>(std::lround(end * options.fps)) + 1;
  out.max_leg_extension = write_frames(
      writer, fig, [&](double time) { return pose_at(time, lift, grip_base); }, frames, options.fps,
      "synth_climb", out.motion);
  for (int f = 0; f < frames; ++f) {
    const BodyPose p = pose_at(f / options.fps, lift, grip_base);
    for (Side side : {kLeft, kRight})
      out.max_arm_extension = std::max(out.max_arm_extension, writer.arm_extension(p, side));
  }
  if (out.max_leg_extension >= PoseWriter::kMaxExtension ||
      out.max_arm_extension >= PoseWriter::kMaxExtension)
    throw std::logic_error("synthesize_climb: a limb cannot reach its hold");
  // A knee stepping up comes forward; it must stay behind the rungs (the ladder is not built with
  // gaps for knees).
  double knee_forward = -1e9;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(fig.skeleton->joint_count()));
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(*fig.skeleton, out.motion.values.row(f), world);
    for (Side side : {kLeft, kRight})
      knee_forward = std::max(knee_forward, world[static_cast<std::size_t>(fig.leg[side])].translation().z());
  }
  const double rung_radius = 0.016;
  if (knee_forward > D - rung_radius) {
    std::ostringstream msg;
    msg << "synthesize_climb: ladder_distance " << D << " m is too close for " << figure_text(H)
        << ": its knees would pass through the ladder (a knee comes " << knee_forward << " m forward)";
    throw std::invalid_argument(msg.str());
  }

  // The ladder, and the holds: each limb holds from the end of one move to the start of its next.
  Ladder& ladder = out.ladder;
  ladder.rung_spacing = s;
  ladder.rail_half_width = w;
  ladder.distance = D;
  ladder.rung_radius = rung_radius;
  // Rungs up to 10 cm above the highest grip, the rails half a spacing above the top rung.
  ladder.rung_count = static_cast<int>(std::ceil((grip_base + n * s + 0.1) / s));
  ladder.rail_top = (ladder.rung_count + 0.5) * s;
  const double t_end = (frames - 1) / options.fps;
  auto add_hold = [&](Side side, bool hand, int level, double t0, double t1) {
    Hold h;
    h.side = side;
    h.hand = hand;
    h.rung = hand ? 0 : level;
    h.joint = hand ? fig.hand[side] : fig.toe[side];
    h.local = hand ? grip_local : sole_local;
    std::tie(h.first_frame, h.last_frame) = frame_span(t0, std::min(t1, t_end), options.fps);
    h.world = hand ? hands[side].at(t0, grip_base) : feet[side].at(t0);
    h.segment_a = hand ? ladder.rail_a(side) : ladder.rung_a(level);
    h.segment_b = hand ? ladder.rail_b(side) : ladder.rung_b(level);
    if (h.first_frame <= h.last_frame) out.holds.push_back(h);
  };
  for (bool hand : {true, false}) {
    for (Side side : {kLeft, kRight}) {
      const std::vector<Move>& ms = hand ? hand_moves[side] : foot_moves[side];
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
  out.steps = n;
  return out;
}

}  // namespace kg::synth
