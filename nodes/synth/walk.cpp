// The synthesized walk (synthesize.hpp): footprints first, feet rolling about heel and ball, the
// pelvis on smooth curves as high as the legs reach, legs by two-link IK.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/synth/synthesize.hpp"
#include "synth_detail.hpp"

namespace kg::synth {

using namespace detail;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A place where a foot lies flat for a while, and how it arrives and leaves.
struct Footprint {
  Eigen::Vector3d ankle;    // ankle centre while flat here, world
  double yaw = 0;           // heading (toe-out)
  double strike = -kInf;    // heel strike (-inf: standing here from the start)
  double flat = -kInf;      // foot flat
  double heel_off = kInf;   // heel rises (inf: stays to the end)
  double toe_off = kInf;    // toes leave
  double strike_pitch = 0;  // foot pitch at heel strike (negative: toes up)
  double off_pitch = 0;     // foot pitch at toe off (heel up)
  double off_rate = 0;      // its rate at toe off, rad/s
};

// One foot: its footprints, and the swings between them.
class FootTrack {
 public:
  FootTrack(const FootGeometry& geometry, std::vector<Footprint> prints, double min_clearance)
      : geo_(geometry), prints_(std::move(prints)), lift_(prints_.size(), 0.0) {
    for (std::size_t i = 0; i + 1 < prints_.size(); ++i) fit_lift(i, min_clearance);
  }

  const std::vector<Footprint>& prints() const { return prints_; }

  // Whether the foot touches the floor at t (heel strike to toe off of some footprint).
  bool on_floor(double t) const {
    for (const Footprint& p : prints_)
      if (t >= p.strike && t <= p.toe_off) return true;
    return false;
  }

  FootState at(double t) const {
    for (std::size_t i = 0; i < prints_.size(); ++i) {
      const Footprint& p = prints_[i];
      if (t < p.strike) return swing(i - 1, t);  // i > 0: the first print has no strike
      if (t <= p.toe_off) return on_print(p, t);
    }
    return on_print(prints_.back(), t);
  }

 private:
  FootState on_print(const Footprint& p, double t) const {
    FootState s;
    s.yaw = p.yaw;
    if (t < p.flat) {  // heel rocker: rolling down about the heel
      const double h = p.flat - p.strike;
      s.pitch = hermite(p.strike_pitch, 0, 0, 0, h, (t - p.strike) / h);
      s.toe_pitch = s.pitch;
      s.ankle = geo_.ankle_about(geo_.heel_when_flat(p.ankle, p.yaw), geo_.heel_offset(), p.yaw, s.pitch);
    } else if (t <= p.heel_off) {
      s.ankle = p.ankle;
    } else {  // heel rise: rolling about the ball, toes flat
      const double h = p.toe_off - p.heel_off;
      s.pitch = hermite(0, 0, p.off_pitch, p.off_rate, h, (t - p.heel_off) / h);
      s.ankle = geo_.ankle_about(geo_.ball_when_flat(p.ankle, p.yaw), geo_.ball_offset(), p.yaw, s.pitch);
    }
    return s;
  }

  // Between prints_[i]'s toe off and prints_[i + 1]'s heel strike, continuing both rolls' rates.
  FootState swing(std::size_t i, double t) const { return swing_at(i, t, lift_[i]); }

  FootState swing_at(std::size_t i, double t, double lift) const {
    const Footprint& a = prints_[i];
    const Footprint& b = prints_[i + 1];
    const double h = b.strike - a.toe_off;
    const double s = std::clamp((t - a.toe_off) / h, 0.0, 1.0);
    const Eigen::Vector3d ball = geo_.ball_when_flat(a.ankle, a.yaw);
    const Eigen::Vector3d a0 = geo_.ankle_about(ball, geo_.ball_offset(), a.yaw, a.off_pitch);
    const Eigen::Vector3d v0 = geo_.ankle_about_dpitch(geo_.ball_offset(), a.yaw, a.off_pitch) * a.off_rate;
    const Eigen::Vector3d a1 =
        geo_.ankle_about(geo_.heel_when_flat(b.ankle, b.yaw), geo_.heel_offset(), b.yaw, b.strike_pitch);
    FootState f;
    f.ankle = hermite(a0, v0, a1, Eigen::Vector3d::Zero(), h, s);
    // Highest before mid-swing (peak at s = 0.4), so the leg can straighten before heel strike;
    // zero slope at both ends keeps C1.
    f.ankle.y() += lift * s * s * (1 - s) * (1 - s) * (1 - s) / 0.03456;
    f.yaw = hermite(a.yaw, 0, b.yaw, 0, h, s);
    f.pitch = hermite(a.off_pitch, a.off_rate, b.strike_pitch, 0, h, s);
    f.toe_pitch = f.pitch + hermite(-a.off_pitch, -a.off_rate, 0, 0, h, s);
    return f;
  }

  // The smallest lift keeping heel, ball and toe tip above the floor all through the swing and
  // `clearance` above it in its middle half.
  void fit_lift(std::size_t i, double clearance) {
    const double t0 = prints_[i].toe_off, t1 = prints_[i + 1].strike;
    std::vector<double> samples;
    for (double e = 1e-4; e < 0.25; e *= 1.5) {
      samples.push_back(e);
      samples.push_back(1 - e);
    }
    for (int k = 1; k < 200; ++k) samples.push_back(k / 200.0);
    double lift = 0.005;
    for (int iter = 0; iter < 60; ++iter, lift *= 1.2) {
      bool ok = true;
      for (double s : samples) {
        const double low = geo_.lowest(swing_at(i, t0 + s * (t1 - t0), lift));
        if (low < 0 || (s >= 0.25 && s <= 0.75 && low < clearance)) {
          ok = false;
          break;
        }
      }
      if (ok) {
        lift_[i] = lift;
        return;
      }
    }
    throw std::logic_error("synthesize_walk: no swing lift clears the floor");
  }

  const FootGeometry& geo_;
  std::vector<Footprint> prints_;
  std::vector<double> lift_;
};

}  // namespace

void WalkOptions::validate() const {
  const WalkOptions& options = *this;
  check_range("walk", "steps", options.steps, kStepsRange.min, kStepsRange.max, "");
  check_range("walk", "speed", options.speed, kSpeedRange.min, kSpeedRange.max, "m/s");
  check_range("walk", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("walk", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");
}

namespace {

// Timeline: stand still, then the pelvis accelerates over one step time to `speed` as the first
// (right) heel strikes; steps follow every T; the closing step lands as the pelvis stops.
struct WalkTimeline {
  int steps = 0;
  double start = 0, stop = 0, settle = 0, end = 0;
  std::vector<double> strike;  // strike[k], k = 1..steps
};

WalkTimeline plan_timeline(int n, const GaitParameters& gait) {
  WalkTimeline tl;
  tl.steps = n;
  tl.start = 0.35;
  tl.strike.resize(static_cast<std::size_t>(n) + 1);
  for (int k = 1; k <= n; ++k) tl.strike[static_cast<std::size_t>(k)] = tl.start + k * gait.step_time;
  tl.stop = tl.strike[static_cast<std::size_t>(n)];
  tl.settle = tl.stop + 0.3;
  tl.end = tl.stop + 0.6;
  return tl;
}

Side step_side(int k) {
  return k % 2 == 1 ? kRight : kLeft;
}

std::array<std::vector<Footprint>, 2> place_footprints(const FigureDimensions& dims,
                                                       const GaitParameters& gait, const WalkTimeline& tl) {
  const int n = tl.steps;
  const double H = dims.stature, v = gait.speed, L = gait.step_length;
  const double stance = gait.stance_time(), swing = gait.swing_time();
  auto step_z = [&](int k) { return std::min(k, n - 1) * L; };
  const double foot_x = 0.035 * H, toe_out = 0.1;
  const double strike_pitch = -std::clamp(0.18 + 0.1 * v, 0.2, 0.4);
  const double off_pitch = std::clamp(0.5 + 0.2 * v, 0.6, 0.95);
  const double rocker = 0.12 * stance, heel_rise = 0.4 * stance;
  std::array<std::vector<Footprint>, 2> prints;
  for (Side side : {kLeft, kRight}) {
    Footprint p;
    p.ankle = Eigen::Vector3d(side_sign(side) * foot_x, dims.ankle_height, 0);
    p.yaw = side_sign(side) * toe_out;
    prints[side].push_back(p);
  }
  for (int k = 1; k <= n; ++k) {
    const Side side = step_side(k);
    Footprint p;
    p.ankle = Eigen::Vector3d(side_sign(side) * foot_x, dims.ankle_height, step_z(k));
    p.yaw = side_sign(side) * toe_out;
    p.strike = tl.strike[static_cast<std::size_t>(k)];
    p.flat = p.strike + rocker;
    p.strike_pitch = k == n ? 0.6 * strike_pitch : strike_pitch;
    Footprint& prev = prints[side].back();
    prev.toe_off = p.strike - swing;
    prev.heel_off = std::max(prev.toe_off - heel_rise, std::isfinite(prev.flat) ? prev.flat + 0.02 : 0.1);
    prev.off_pitch = off_pitch;
    prev.off_rate = 2 * off_pitch / (prev.toe_off - prev.heel_off);
    prints[side].push_back(p);
  }
  return prints;
}

// Pelvis: forward progress (exactly `speed` from the first to the last full step), `z_bias` ahead
// of the feet when standing.
Curve forward_progress(const WalkTimeline& tl, const GaitParameters& gait, double z_bias) {
  const int n = tl.steps;
  const double v = gait.speed, L = gait.step_length;
  const std::vector<double>& strike = tl.strike;
  Curve z;
  z.add_hold(0, tl.start, z_bias);
  z.add_quintic(tl.start, strike[1], z_bias, 0, 0, z_bias + 0.5 * L, v, 0);
  if (n > 2)
    z.add_poly(strike[1], strike[static_cast<std::size_t>(n - 1)], {z_bias + 0.5 * L, v, 0, 0, 0, 0});
  z.add_quintic(strike[static_cast<std::size_t>(n - 1)], tl.stop, z_bias + (n - 1.5) * L, v, 0,
                z_bias + (n - 1) * L, 0, 0);
  z.add_hold(tl.stop, tl.end, z_bias + (n - 1) * L);
  return z;
}

double speed_scale(const GaitParameters& gait) {
  return std::clamp(gait.speed / 1.3, 0.4, 1.5);
}

struct PelvisCurves {
  Curve x, yaw, roll, pitch, lean;
};

// The pelvis sways over the stance foot at mid-swing, rotates forward on the side of the landing
// foot, lists down on the swing side and tilts forward; the trunk counter-rotates (pose_at) and
// leans forward.
PelvisCurves pelvis_curves(const WalkTimeline& tl, const GaitParameters& gait, double H) {
  const int n = tl.steps;
  const double v = gait.speed, swing = gait.swing_time();
  const std::vector<double>& strike = tl.strike;
  const double sway = 0.0125 * H * std::min(std::sqrt(1.3 / v), 1.3);
  const double yaw_amp = 0.07 * speed_scale(gait), list_amp = 0.06 * speed_scale(gait);
  const double tilt_stand = 0.03, tilt_walk = 0.03 + 0.03 * v;
  const double lean_stand = 0.0, lean_walk = 0.02 + 0.02 * v;
  std::vector<std::pair<double, double>> kx{{0.1, 0}}, kyaw{{tl.start, 0}}, kroll{{tl.start, 0}};
  std::vector<std::pair<double, double>> kpitch{{tl.start, tilt_stand}}, klean{{tl.start, lean_stand}};
  for (int k = 1; k <= n; ++k) {
    const Side side = step_side(k);
    const double sgn = side == kRight ? 1.0 : -1.0;  // right heel strike: right hip forward
    const double t = strike[static_cast<std::size_t>(k)];
    const double mid_swing = t - swing / 2;
    const double scale = k == n ? 0.4 : 1.0;  // the closing step is a small one
    kx.push_back({mid_swing, -side_sign(side) * sway * scale});
    kroll.push_back({mid_swing, sgn * list_amp * scale});
    kyaw.push_back({t, sgn * yaw_amp * scale});
  }
  if (n > 1) {
    kpitch.push_back({strike[1], tilt_walk});
    klean.push_back({strike[1], lean_walk});
  }
  if (n > 2) {
    kpitch.push_back({strike[static_cast<std::size_t>(n - 1)], tilt_walk});
    klean.push_back({strike[static_cast<std::size_t>(n - 1)], lean_walk});
  }
  for (auto* keys : {&kx, &kyaw, &kroll}) keys->push_back({tl.settle, 0});
  kpitch.push_back({tl.settle, tilt_stand});
  klean.push_back({tl.settle, lean_stand});
  return {monotone_curve(kx), monotone_curve(kyaw), monotone_curve(kroll), monotone_curve(kpitch),
          monotone_curve(klean)};
}

struct ArmCurves {
  std::array<Curve, 2> flex, elbow;
};

// The arms swing against the legs.
ArmCurves arm_curves(const WalkTimeline& tl, const GaitParameters& gait) {
  const int n = tl.steps;
  const double arm_amp = 0.28 * speed_scale(gait), arm_mean = -0.05;
  std::array<std::vector<std::pair<double, double>>, 2> kflex, kelbow;
  for (Side side : {kLeft, kRight}) {
    kflex[side] = {{tl.start, 0}};
    kelbow[side] = {{tl.start, 0.1}};
  }
  for (int k = 1; k <= n; ++k) {
    const Side side = step_side(k);
    const double t = tl.strike[static_cast<std::size_t>(k)];
    const double scale = k == n ? 0.4 : 1.0;  // the closing step is a small one
    const Side other = side == kLeft ? kRight : kLeft;
    kflex[side].push_back({t, (arm_mean - arm_amp) * scale});
    kflex[other].push_back({t, (arm_mean + arm_amp) * scale});
    kelbow[side].push_back({t, 0.2});
    kelbow[other].push_back({t, 0.2 + 0.3 * speed_scale(gait) * scale});
  }
  for (Side side : {kLeft, kRight}) {
    kflex[side].push_back({tl.stop + 0.45, 0});
    kelbow[side].push_back({tl.stop + 0.45, 0.1});
  }
  return {{monotone_curve(kflex[kLeft]), monotone_curve(kflex[kRight])},
          {monotone_curve(kelbow[kLeft]), monotone_curve(kelbow[kRight])}};
}

// Everything a pose of the walk comes from but the pelvis height.
struct Walk {
  const Figure& fig;
  const GaitParameters& gait;
  const WalkTimeline& timeline;
  const std::array<FootTrack, 2>& feet;
  double z_bias = 0;  // hips slightly ahead of the ankles, as when standing
  Curve z;
  PelvisCurves pelvis;
  ArmCurves arms;
};

// Planted legs reach with at most this of their length.
constexpr double kLimit = 0.998;

// A swinging foot's target drawn towards the hip where it would stretch the leg past kLimit
// (just after toe off, when the hips run ahead), saturating smoothly (tanh: C2) below the IK's
// reach. The planted feet never exceed kLimit (the pelvis height search sees to it), so the
// swing starts and ends untouched.
void draw_in(const Walk& w, BodyPose& p, Side side) {
  const double reach = 0.999 * w.fig.dims.leg_length(), soft = kLimit * w.fig.dims.leg_length();
  const Eigen::Vector3d hip = p.root + p.pelvis * w.fig.skeleton->joint(w.fig.up_leg[side]).offset;
  const Eigen::Vector3d d = p.feet[side].ankle - hip;
  const double D = d.norm();
  if (D <= soft) return;
  p.feet[side].ankle = hip + d * ((soft + (reach - soft) * std::tanh((D - soft) / (reach - soft))) / D);
}

BodyPose pose_at(const Walk& w, double t, const Curve& height) {
  const PelvisCurves& pelvis = w.pelvis;
  BodyPose p;
  p.root = Eigen::Vector3d(pelvis.x.value(t), height.value(t), w.z.value(t));
  const double yw = pelvis.yaw.value(t);
  p.pelvis = rot_y(yw) * rot_z(pelvis.roll.value(t)) * rot_x(pelvis.pitch.value(t));
  p.chest = rot_y(-0.6 * yw) * rot_x(pelvis.lean.value(t));
  p.head = rot_x(0.02);
  for (Side side : {kLeft, kRight}) {
    p.arms[side] = {0.1, w.arms.flex[side].value(t), w.arms.elbow[side].value(t)};
    p.feet[side] = w.feet[side].at(t);
    if (!w.feet[side].on_floor(t)) draw_in(w, p, side);
  }
  return p;
}

// Walking, the pelvis is low (`low`) in the middle of each double support and high (`high`, at
// most standing) in single support as it passes over the stance ankle.
Curve height_curve(const Walk& w, double y_stand, double low, double high) {
  const WalkTimeline& tl = w.timeline;
  const int n = tl.steps;
  const double v = w.gait.speed, T = w.gait.step_time, L = w.gait.step_length;
  const double swing = w.gait.swing_time(), dsupport = w.gait.double_support_time();
  high = std::min(high, y_stand);
  std::vector<std::pair<double, double>> keys{{tl.start, y_stand}, {tl.strike[1] - swing, high}};
  for (int k = 1; k < n; ++k) {
    const double t = tl.strike[static_cast<std::size_t>(k)];
    keys.push_back({t + dsupport / 2, low});
    if (k + 1 < n) {
      const double over_ankle = t + (0.5 * L - w.z_bias) / v;  // pelvis above the stance ankle
      keys.push_back({std::clamp(over_ankle, t + dsupport, t + T - 0.5 * dsupport), high});
    }
  }
  keys.push_back({tl.settle, y_stand});
  return monotone_curve(keys);
}

// The largest extension of a planted leg over the walk.
double worst_extension(const Walk& w, const PoseWriter& writer, const Curve& height) {
  // Sampled at a fixed rate, not at `fps`, so every frame rate gets the same curves.
  const double search_rate = 240, end = w.timeline.end;
  const int search_samples = static_cast<int>(std::ceil(end * search_rate)) + 1;
  double worst = 0;
  for (int i = 0; i < search_samples; ++i) {
    const double t = std::min(i / search_rate, end);
    const BodyPose p = pose_at(w, t, height);
    for (Side side : {kLeft, kRight})
      if (w.feet[side].on_floor(t)) worst = std::max(worst, writer.leg_extension(p, side));
  }
  return worst;
}

// Pelvis height: standing with the legs at 0.996 of their length. Walking, first the low level is
// raised as far as the planted legs reach with at most kLimit of their length (knees bent at
// least 7 degrees) keeping a bob of 6 % of the step length, then the high level as far as they
// reach. Swinging legs do not bound it: their targets are drawn in (draw_in).
Curve fit_pelvis_height(const Walk& w, const PoseWriter& writer) {
  const FigureDimensions& dims = w.fig.dims;
  const double leg = dims.leg_length();
  const BodyPose stand = pose_at(w, 0, monotone_curve({{0, 0}}));
  const double y_stand = root_height_for(writer, stand, 0.996, 0, dims.stature);
  auto worst = [&](double low, double high) {
    return worst_extension(w, writer, height_curve(w, y_stand, low, high));
  };
  const double bob = 0.06 * w.gait.step_length;
  double lo = y_stand - 0.4 * leg, hi = y_stand;
  if (worst(lo, lo + bob) > kLimit)
    throw std::logic_error("synthesize_walk: the legs cannot reach the footprints");
  for (int i = 0; i < 40; ++i) {
    const double mid = (lo + hi) / 2;
    (worst(mid, mid + bob) <= kLimit ? lo : hi) = mid;
  }
  const double low = lo;
  lo = low + bob;
  hi = y_stand;
  for (int i = 0; i < 40; ++i) {
    const double mid = (lo + hi) / 2;
    (worst(low, mid) <= kLimit ? lo : hi) = mid;
  }
  return height_curve(w, y_stand, low, lo);
}

// Plants: heel from strike to heel off, ankle from foot flat to heel off, ball and toe tip from
// foot flat to toe off.
void record_plants(const Walk& w, const FootGeometry& geo, double fps, int frames,
                   std::vector<FootPlant>& out) {
  PlantRecorder plants(w.fig, fps, frames, out);
  for (Side side : {kLeft, kRight}) {
    for (const Footprint& p : w.feet[side].prints()) {
      const Eigen::Vector3d ball = geo.ball_when_flat(p.ankle, p.yaw);
      const double flat = std::max(p.flat, 0.0);
      plants.add(side, FootPoint::Heel, std::max(p.strike, 0.0), p.heel_off,
                 geo.heel_when_flat(p.ankle, p.yaw));
      plants.add(side, FootPoint::Ankle, flat, p.heel_off, p.ankle);
      plants.add(side, FootPoint::Ball, flat, p.toe_off, ball);
      plants.add(side, FootPoint::Toe, flat, p.toe_off, ball + rot_y(p.yaw) * w.fig.toe_tip_local);
    }
  }
}

}  // namespace

GaitParameters gait_from_speed(double speed, double stature) {
  check_range("walk", "speed", speed, kSpeedRange.min, kSpeedRange.max, "m/s");
  check_range("walk", "stature", stature, kStatureRange.min, kStatureRange.max, "m");
  GaitParameters g;
  g.speed = speed;
  const double walk_ratio = 0.0037 * stature;                      // m per (step/min)
  const double cadence = std::sqrt(60 * speed / walk_ratio) / 60;  // steps/s
  g.step_time = 1 / cadence;
  g.step_length = speed * g.step_time;
  g.stance_fraction = std::clamp(0.655 - 0.04 * speed, 0.56, 0.66);
  return g;
}

const char* to_string(FootPoint point) {
  switch (point) {
    case FootPoint::Heel:
      return "Heel";
    case FootPoint::Ankle:
      return "Ankle";
    case FootPoint::Ball:
      return "Ball";
    case FootPoint::Toe:
      return "Toe";
  }
  return "?";
}

std::string FootPlant::name() const {
  return std::string(side_name(side)) + to_string(point);
}

Synthesis synthesize_walk(const WalkOptions& options) {
  options.validate();
  Synthesis out;
  out.figure = make_figure(options.stature);
  const Figure& fig = out.figure;
  const double H = fig.dims.stature;
  out.gait = gait_from_speed(options.speed, options.stature);
  const GaitParameters& gait = out.gait;
  const FootGeometry geo(fig);
  PoseWriter writer(fig);

  const WalkTimeline timeline = plan_timeline(options.steps, gait);
  const std::array<std::vector<Footprint>, 2> prints = place_footprints(fig.dims, gait, timeline);
  const double clearance = 0.015 * H / 1.75;
  const std::array<FootTrack, 2> feet{FootTrack(geo, prints[kLeft], clearance),
                                      FootTrack(geo, prints[kRight], clearance)};
  const double z_bias = 0.02 * H;
  const Walk walk{fig,
                  gait,
                  timeline,
                  feet,
                  z_bias,
                  forward_progress(timeline, gait, z_bias),
                  pelvis_curves(timeline, gait, H),
                  arm_curves(timeline, gait)};
  const Curve height = fit_pelvis_height(walk, writer);

  const int frames = static_cast<int>(std::lround(timeline.end * options.fps)) + 1;
  out.max_leg_extension = write_frames(
      writer, fig, [&](double t) { return pose_at(walk, t, height); }, frames, options.fps, "synth_walk",
      out.motion);
  record_plants(walk, geo, options.fps, frames, out.plants);
  const int n = options.steps;
  out.steps = n;
  if (n >= 3) {
    out.steady_start = timeline.strike[1];
    out.steady_end = timeline.strike[static_cast<std::size_t>(n - 1)];
  }
  return out;
}

}  // namespace kg::synth
