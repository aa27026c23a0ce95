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
  check_range("walk", "steps", options.steps, kStepsRange.min, kStepsRange.max, "");
  check_range("walk", "speed", options.speed, kSpeedRange.min, kSpeedRange.max, "m/s");
  check_range("walk", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("walk", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");

  Synthesis out;
  out.figure = make_figure(options.stature);
  const Figure& fig = out.figure;
  const FigureDimensions& dims = fig.dims;
  const double H = dims.stature;
  const GaitParameters gait = gait_from_speed(options.speed, options.stature);
  out.gait = gait;
  const FootGeometry geo(fig);
  PoseWriter writer(fig);

  const int n = options.steps;
  const double v = gait.speed, T = gait.step_time, L = gait.step_length;
  const double stance = gait.stance_time(), swing = gait.swing_time(), dsupport = gait.double_support_time();
  // Timeline: stand still, then the pelvis accelerates over one step time to `speed` as the first
  // (right) heel strikes; steps follow every T; the closing step lands as the pelvis stops.
  const double start = 0.35;
  std::vector<double> strike(static_cast<std::size_t>(n) + 1);  // strike[k], k = 1..n
  for (int k = 1; k <= n; ++k) strike[static_cast<std::size_t>(k)] = start + k * T;
  const double stop = strike[static_cast<std::size_t>(n)];
  const double settle = stop + 0.3;
  const double end = stop + 0.6;
  auto step_side = [](int k) { return k % 2 == 1 ? kRight : kLeft; };
  auto step_z = [&](int k) { return std::min(k, n - 1) * L; };

  // Footprints.
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
    p.strike = strike[static_cast<std::size_t>(k)];
    p.flat = p.strike + rocker;
    p.strike_pitch = k == n ? 0.6 * strike_pitch : strike_pitch;
    Footprint& prev = prints[side].back();
    prev.toe_off = p.strike - swing;
    prev.heel_off = std::max(prev.toe_off - heel_rise, std::isfinite(prev.flat) ? prev.flat + 0.02 : 0.1);
    prev.off_pitch = off_pitch;
    prev.off_rate = 2 * off_pitch / (prev.toe_off - prev.heel_off);
    prints[side].push_back(p);
  }
  const double clearance = 0.015 * H / 1.75;
  const std::array<FootTrack, 2> feet{FootTrack(geo, prints[kLeft], clearance),
                                      FootTrack(geo, prints[kRight], clearance)};

  // Pelvis: forward progress (exactly `speed` from the first to the last full step), sway over the
  // stance foot at mid-swing, rotation forward on the side of the landing foot, list down on the
  // swing side, anterior tilt; the trunk counter-rotates, the arms swing against the legs.
  const double z_bias = 0.02 * H;  // hips slightly ahead of the ankles, as when standing
  Curve z;
  z.add_hold(0, start, z_bias);
  z.add_quintic(start, strike[1], z_bias, 0, 0, z_bias + 0.5 * L, v, 0);
  if (n > 2)
    z.add_poly(strike[1], strike[static_cast<std::size_t>(n - 1)], {z_bias + 0.5 * L, v, 0, 0, 0, 0});
  z.add_quintic(strike[static_cast<std::size_t>(n - 1)], stop, z_bias + (n - 1.5) * L, v, 0,
                z_bias + (n - 1) * L, 0, 0);
  z.add_hold(stop, end, z_bias + (n - 1) * L);

  const double speed_scale = std::clamp(v / 1.3, 0.4, 1.5);
  const double sway = 0.0125 * H * std::min(std::sqrt(1.3 / v), 1.3);
  const double yaw_amp = 0.07 * speed_scale, list_amp = 0.06 * speed_scale;
  const double arm_amp = 0.28 * speed_scale, arm_mean = -0.05;
  const double tilt_stand = 0.03, tilt_walk = 0.03 + 0.03 * v;
  const double lean_stand = 0.0, lean_walk = 0.02 + 0.02 * v;
  std::vector<std::pair<double, double>> kx{{0.1, 0}}, kyaw{{start, 0}}, kroll{{start, 0}};
  std::vector<std::pair<double, double>> kpitch{{start, tilt_stand}}, klean{{start, lean_stand}};
  std::array<std::vector<std::pair<double, double>>, 2> kflex, kelbow;
  for (Side side : {kLeft, kRight}) {
    kflex[side] = {{start, 0}};
    kelbow[side] = {{start, 0.1}};
  }
  for (int k = 1; k <= n; ++k) {
    const Side side = step_side(k);
    const double sgn = side == kRight ? 1.0 : -1.0;  // right heel strike: right hip forward
    const double t = strike[static_cast<std::size_t>(k)];
    const double mid_swing = t - swing / 2;
    const double scale = k == n ? 0.4 : 1.0;  // the closing step is a small one
    kx.push_back({mid_swing, -side_sign(side) * sway * scale});
    kroll.push_back({mid_swing, sgn * list_amp * scale});
    kyaw.push_back({t, sgn * yaw_amp * scale});
    const Side other = side == kLeft ? kRight : kLeft;
    kflex[side].push_back({t, (arm_mean - arm_amp) * scale});
    kflex[other].push_back({t, (arm_mean + arm_amp) * scale});
    kelbow[side].push_back({t, 0.2});
    kelbow[other].push_back({t, 0.2 + 0.3 * speed_scale * scale});
  }
  if (n > 1) {
    kpitch.push_back({strike[1], tilt_walk});
    klean.push_back({strike[1], lean_walk});
  }
  if (n > 2) {
    kpitch.push_back({strike[static_cast<std::size_t>(n - 1)], tilt_walk});
    klean.push_back({strike[static_cast<std::size_t>(n - 1)], lean_walk});
  }
  for (auto* keys : {&kx, &kyaw, &kroll}) keys->push_back({settle, 0});
  kpitch.push_back({settle, tilt_stand});
  klean.push_back({settle, lean_stand});
  for (Side side : {kLeft, kRight}) {
    kflex[side].push_back({stop + 0.45, 0});
    kelbow[side].push_back({stop + 0.45, 0.1});
  }
  const Curve x = monotone_curve(kx), yaw = monotone_curve(kyaw), roll = monotone_curve(kroll);
  const Curve pitch = monotone_curve(kpitch), lean = monotone_curve(klean);
  const std::array<Curve, 2> flex{monotone_curve(kflex[kLeft]), monotone_curve(kflex[kRight])};
  const std::array<Curve, 2> elbow{monotone_curve(kelbow[kLeft]), monotone_curve(kelbow[kRight])};

  // A swinging foot's target drawn towards the hip where it would stretch the leg past `limit`
  // (just after toe off, when the hips run ahead), saturating smoothly (tanh: C2) below the IK's
  // reach. The planted feet never exceed `limit` (the pelvis height search sees to it), so the
  // swing starts and ends untouched.
  const double limit = 0.998, reach = 0.999 * dims.leg_length(), soft = limit * dims.leg_length();
  auto draw_in = [&](BodyPose& p, Side side) {
    const Eigen::Vector3d hip = p.root + p.pelvis * fig.skeleton->joint(fig.up_leg[side]).offset;
    const Eigen::Vector3d d = p.feet[side].ankle - hip;
    const double D = d.norm();
    if (D <= soft) return;
    p.feet[side].ankle = hip + d * ((soft + (reach - soft) * std::tanh((D - soft) / (reach - soft))) / D);
  };
  auto pose_at = [&](double t, const Curve& height) {
    BodyPose p;
    p.root = Eigen::Vector3d(x.value(t), height.value(t), z.value(t));
    const double yw = yaw.value(t);
    p.pelvis = rot_y(yw) * rot_z(roll.value(t)) * rot_x(pitch.value(t));
    p.chest = rot_y(-0.6 * yw) * rot_x(lean.value(t));
    p.head = rot_x(0.02);
    for (Side side : {kLeft, kRight}) {
      p.arms[side] = {0.1, flex[side].value(t), elbow[side].value(t)};
      p.feet[side] = feet[side].at(t);
      if (!feet[side].on_floor(t)) draw_in(p, side);
    }
    return p;
  };

  // Pelvis height: standing with the legs at 0.996 of their length. Walking, low in the middle of
  // each double support and high in single support as the pelvis passes over the stance ankle;
  // first the low level is raised as far as the planted legs reach with at most 0.998 of their
  // length (knees bent at least 7 degrees) keeping a bob of 6 % of the step length, then the high
  // level as far as they reach. Swinging legs do not bound it: their targets are drawn in (below).
  const double leg = dims.leg_length();
  const BodyPose stand = pose_at(0, monotone_curve({{0, 0}}));
  const double y_stand = root_height_for(writer, stand, 0.996, 0, dims.stature);
  auto height_curve = [&](double low, double high) {
    high = std::min(high, y_stand);
    std::vector<std::pair<double, double>> keys{{start, y_stand}, {strike[1] - swing, high}};
    for (int k = 1; k < n; ++k) {
      const double t = strike[static_cast<std::size_t>(k)];
      keys.push_back({t + dsupport / 2, low});
      if (k + 1 < n) {
        const double over_ankle = t + (0.5 * L - z_bias) / v;  // pelvis above the stance ankle
        keys.push_back({std::clamp(over_ankle, t + dsupport, t + T - 0.5 * dsupport), high});
      }
    }
    keys.push_back({settle, y_stand});
    return monotone_curve(keys);
  };
  const int frames = static_cast<int>(std::lround(end * options.fps)) + 1;
  // Sampled at a fixed rate, not at `fps`, so every frame rate gets the same curves.
  const double search_rate = 240;
  const int search_samples = static_cast<int>(std::ceil(end * search_rate)) + 1;
  auto worst_extension = [&](const Curve& height) {
    double worst = 0;
    for (int i = 0; i < search_samples; ++i) {
      const double t = std::min(i / search_rate, end);
      const BodyPose p = pose_at(t, height);
      for (Side side : {kLeft, kRight})
        if (feet[side].on_floor(t)) worst = std::max(worst, writer.leg_extension(p, side));
    }
    return worst;
  };
  const double bob = 0.06 * L;
  double lo = y_stand - 0.4 * leg, hi = y_stand;
  if (worst_extension(height_curve(lo, lo + bob)) > limit)
    throw std::logic_error("synthesize_walk: the legs cannot reach the footprints");
  for (int i = 0; i < 40; ++i) {
    const double mid = (lo + hi) / 2;
    (worst_extension(height_curve(mid, mid + bob)) <= limit ? lo : hi) = mid;
  }
  const double low = lo;
  lo = low + bob;
  hi = y_stand;
  for (int i = 0; i < 40; ++i) {
    const double mid = (lo + hi) / 2;
    (worst_extension(height_curve(low, mid)) <= limit ? lo : hi) = mid;
  }
  const Curve height = height_curve(low, lo);

  out.max_leg_extension = write_frames(
      writer, fig, [&](double t) { return pose_at(t, height); }, frames, options.fps, "synth_walk",
      out.motion);

  // Plants: heel from strike to heel off, ankle from foot flat to heel off, ball and toe tip from
  // foot flat to toe off.
  PlantRecorder plants(fig, options.fps, frames, out.plants);
  for (Side side : {kLeft, kRight}) {
    for (const Footprint& p : feet[side].prints()) {
      const Eigen::Vector3d ball = geo.ball_when_flat(p.ankle, p.yaw);
      const double flat = std::max(p.flat, 0.0);
      plants.add(side, FootPoint::Heel, std::max(p.strike, 0.0), p.heel_off,
                 geo.heel_when_flat(p.ankle, p.yaw));
      plants.add(side, FootPoint::Ankle, flat, p.heel_off, p.ankle);
      plants.add(side, FootPoint::Ball, flat, p.toe_off, ball);
      plants.add(side, FootPoint::Toe, flat, p.toe_off, ball + rot_y(p.yaw) * fig.toe_tip_local);
    }
  }
  out.steps = n;
  if (n >= 3) {
    out.steady_start = strike[1];
    out.steady_end = strike[static_cast<std::size_t>(n - 1)];
  }
  return out;
}

}  // namespace kg::synth
