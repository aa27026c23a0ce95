// The synthesized standing jump (synthesize.hpp): stand, countermovement, push-off onto the balls
// of the feet, a flight whose centre of mass falls freely, landing on the balls, heels down, absorbing
// crouch, stand.
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "kg/body/body_build.hpp"
#include "kg/synth/synthesize.hpp"
#include "synth_detail.hpp"

namespace kg::synth {

using namespace detail;

namespace {

// Foot pitches (heel up) at takeoff, at the tuck and at touchdown; the heels come down in
// kHeelDrop seconds after touchdown, starting at the rate kLandingRate.
constexpr double kOffPitch = 0.8, kTuckPitch = 0.3, kLandPitch = 0.35, kHeelDrop = 0.12;
constexpr double kLandingRate = -1.5 * kLandPitch / kHeelDrop;
// Pelvis pitch standing and at touchdown.
constexpr double kTiltStand = 0.03, kPitchLand = 0.15;

// What every stage works from: the figure, the jump asked for, and the feet where they stand
// before the jump (start) and after it (land).
struct JumpSetting {
  const Figure& fig;
  FootGeometry geo;
  double leg = 0;  // thigh + shank
  double g = 0, height = 0, distance = 0;
  double vy = 0;      // the root's upward speed at takeoff, rising `height` to the apex
  double foot_x = 0;  // each ankle's distance from the middle, sideways
  std::array<double, 2> yaw{};
  std::array<Eigen::Vector3d, 2> ankle_start{}, ball_start{}, ankle_land{}, ball_land{};
  Eigen::Vector3d hip_offset{};  // left; mirrored for right
  double z_stand = 0, y_stand = 0;
};

}  // namespace

void JumpOptions::validate() const {
  const JumpOptions& options = *this;
  check_range("jump", "height", options.height, kJumpHeightRange.min, kJumpHeightRange.max, "m");
  check_range("jump", "distance", options.distance, kJumpDistanceRange.min, kJumpDistanceRange.max, "m");
  check_range("jump", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("jump", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");
  check_range("jump", "gravity", options.gravity, kGravityRange.min, kGravityRange.max, "m/s^2");
}

namespace {

BodyPose standing_pose(const JumpSetting& s, double z) {
  BodyPose p;
  p.root = Eigen::Vector3d(0, 0, z);
  p.pelvis = rot_x(kTiltStand);
  for (Side side : {kLeft, kRight}) p.feet[side] = {s.ankle_start[side], s.yaw[side], 0, 0};
  return p;
}

// Feet: hip width apart, toes slightly out; they land `distance` further along +Z. Standing root:
// legs at 0.996 of their length (as the walk's), hips a little ahead of the ankles.
JumpSetting place_feet(const Figure& fig, const JumpOptions& options, const PoseWriter& writer) {
  const double H = fig.dims.stature;
  JumpSetting s{.fig = fig,
                .geo = FootGeometry(fig),
                .leg = fig.dims.leg_length(),
                .g = options.gravity,
                .height = options.height,
                .distance = options.distance,
                .vy = std::sqrt(2 * options.gravity * options.height),
                .foot_x = 0.055 * H};
  const double toe_out = 0.12;
  for (Side side : {kLeft, kRight}) {
    s.yaw[side] = side_sign(side) * toe_out;
    s.ankle_start[side] = Eigen::Vector3d(side_sign(side) * s.foot_x, fig.dims.ankle_height, 0);
    s.ankle_land[side] = s.ankle_start[side] + Eigen::Vector3d(0, 0, s.distance);
    s.ball_start[side] = s.geo.ball_when_flat(s.ankle_start[side], s.yaw[side]);
    s.ball_land[side] = s.geo.ball_when_flat(s.ankle_land[side], s.yaw[side]);
  }
  s.hip_offset = fig.skeleton->joint(fig.up_leg[kLeft]).offset;
  s.z_stand = 0.02 * H;
  s.y_stand = root_height_for(writer, standing_pose(s, s.z_stand), 0.996, 0, H);
  return s;
}

// The takeoff and touchdown of one forward takeoff speed vz: the root and the left ball joint
// (relative to the root) at both, and the flight between them.
struct Flight {
  double vz = 0, v_land = 0, flight = 0, reach_time = 0, reach_pitch = 0, lean_off = 0, pitch_off = 0;
  Eigen::Vector3d root_off, root_land, ball_rel_off, ball_rel_reach, ball_rel_land;
  double implied_vz = 0;
};

// The point of a leg `extension` long from the hip, leaning `lean` (forward positive) in the
// sagittal plane (the ankle behind the hip for lean > 0), with the hip at hip_rel from the root
// and the ankle at sideways position ankle_x: the ankle relative to the root.
Eigen::Vector3d ankle_from_hip(const JumpSetting& s, const Eigen::Vector3d& hip_rel, double extension,
                               double lean, double ankle_x) {
  const double dx = ankle_x - hip_rel.x();
  const double r = std::sqrt(std::pow(extension * s.leg, 2) - dx * dx);
  return Eigen::Vector3d(hip_rel.x() + dx, hip_rel.y() - r * std::cos(lean),
                         hip_rel.z() - r * std::sin(lean));
}

// Takeoff: the ball on the floor, the foot pitched kOffPitch, the leg leaning forward.
void place_takeoff(const JumpSetting& s, double takeoff_extension, Flight& f) {
  f.lean_off = 0.55 * std::atan2(f.vz, s.vy);
  f.pitch_off = 0.05 + 0.5 * f.lean_off;
  const Eigen::Vector3d ankle_off =
      s.geo.ankle_about(s.ball_start[kLeft], s.geo.ball_offset(), s.yaw[kLeft], kOffPitch);
  const Eigen::Vector3d hip_rel_off = rot_x(f.pitch_off) * s.hip_offset;
  f.root_off = ankle_off - ankle_from_hip(s, hip_rel_off, takeoff_extension, f.lean_off, ankle_off.x());
  f.root_off.x() = 0;
  f.ball_rel_off = s.ball_start[kLeft] - f.root_off;
}

// Touchdown: reach_time before it the leg reaches `extension` long, feet ahead; then the foot
// decelerates to rest while the root keeps falling, so relative to the root it rises and draws
// back. Sets the landing root height for a reach of `extension`.
void place_touchdown(const JumpSetting& s, double extension, Flight& f) {
  const double lean_land = -0.45 * std::atan2(f.vz, std::abs(f.v_land));
  const Eigen::Vector3d hip_rel_land = rot_x(kPitchLand) * s.hip_offset;
  f.ball_rel_reach = ankle_from_hip(s, hip_rel_land, extension, lean_land, s.foot_x) +
                     rot_y(s.yaw[kLeft]) * (rot_x(f.reach_pitch) * s.geo.ball_offset());
  f.ball_rel_reach.x() = s.ball_land[kLeft].x();  // the root flies at x = 0: no sideways jump at touchdown
  f.ball_rel_land = f.ball_rel_reach +
                    Eigen::Vector3d(0, std::abs(f.v_land) * f.reach_time / 2.5, -f.vz * f.reach_time / 2.5);
  f.root_land = s.ball_land[kLeft] - f.ball_rel_land;
  f.root_land.x() = 0;
}

// The landing geometry and the flight time settle by fixed-point iteration (weakly coupled
// through the landing speed).
void settle_touchdown(const JumpSetting& s, Flight& f) {
  f.v_land = -s.vy;
  f.flight = 2 * s.vy / s.g;
  for (int iter = 0; iter < 100; ++iter) {
    f.reach_time = std::min(0.08, 0.2 * f.flight);
    f.reach_pitch = kLandPitch + std::abs(kLandingRate) * f.reach_time / 2.5;
    place_touchdown(s, 0.96, f);
    // A low hop lands no higher than half way up to its apex: the legs reach less far.
    const double ceiling = f.root_off.y() + 0.5 * s.height;
    if (f.root_land.y() > ceiling) {
      double lo = 0.5, hi = 0.96;
      for (int i = 0; i < 50; ++i) {
        place_touchdown(s, (lo + hi) / 2, f);
        (f.root_land.y() > ceiling ? hi : lo) = (lo + hi) / 2;
      }
      place_touchdown(s, lo, f);
    }
    const double drop = f.root_off.y() - f.root_land.y();
    const double flight = (s.vy + std::sqrt(s.vy * s.vy + 2 * s.g * drop)) / s.g;
    const bool settled = std::abs(flight - f.flight) < 1e-14;
    f.flight = flight;
    f.v_land = s.vy - s.g * flight;
    if (settled) break;
  }
}

Flight flight_for(const JumpSetting& s, double takeoff_extension, double vz) {
  Flight f;
  f.vz = vz;
  place_takeoff(s, takeoff_extension, f);
  settle_touchdown(s, f);
  f.implied_vz = (f.root_land.z() - f.root_off.z()) / f.flight;
  return f;
}

// Takeoff and touchdown: the root's height and forward speed follow from the legs' geometry at
// both instants, which leans with the forward speed vz. The vz the geometry implies falls as vz
// rises, so bisection finds the consistent one.
Flight solve_flight(const JumpSetting& s, double takeoff_extension) {
  const double vy = s.vy;
  double vz_lo = -3, vz_hi = 3 * vy + 1;
  for (int i = 0; i < 80; ++i) {
    const double mid = (vz_lo + vz_hi) / 2;
    (flight_for(s, takeoff_extension, mid).implied_vz > mid ? vz_lo : vz_hi) = mid;
  }
  const Flight fl = flight_for(s, takeoff_extension, (vz_lo + vz_hi) / 2);
  // Standing long jumps leave at 30-45 degrees; flatter than about 27 (forward speed over twice
  // the upward one) is no standing jump this figure can do.
  if (fl.vz > 2 * vy) {
    std::ostringstream msg;
    msg << "synthesize_jump: distance " << s.distance << " m with height " << s.height
        << " m needs a forward takeoff speed of " << (fl.vz < vz_hi - 1e-6 ? "" : "over ") << fl.vz
        << " m/s, more than twice the upward " << vy << " m/s: raise the height or shorten the distance";
    throw std::invalid_argument(msg.str());
  }
  return fl;
}

// The timeline (seconds), with the root's height and forward position at the bottoms of the
// countermovement (low) and of the landing crouch (absorb).
struct Phases {
  double t_dip = 0, t_low = 0, t_heel = 0, t_off = 0, t_tuck = 0, t_reach = 0, t_land = 0;
  double t_absorbed = 0, t_stood = 0, end = 0;
  double off_rate = 0;  // the feet's pitch rate at takeoff
  double depth = 0, y_low = 0, z_low = 0, y_absorb = 0, z_absorb = 0;
};

// Durations of the push-off and of the absorbing crouch: among the quintics moving the root one
// way only (the hips neither dip before rising nor bounce at the bottom), the one of least peak
// acceleration.
double gentlest_duration(const char* phase, double y0, double v0, double a0, double y1, double v1,
                         double a1) {
  const double sign = y1 > y0 ? 1 : -1;
  double best = -1, best_peak = 0;
  for (double T = 0.08; T < 1.0; T += 0.005) {
    Curve c;
    c.add_quintic(0, T, y0, v0, a0, y1, v1, a1);
    bool ok = true;
    double peak = 0;
    for (int i = 0; i <= 100 && ok; ++i) {
      ok = i == 0 || sign * c.slope(T * i / 100) >= 0;
      peak = std::max(peak, std::abs(c.second(T * i / 100)));
    }
    if (ok && (best < 0 || peak < best_peak)) {
      best = T;
      best_peak = peak;
    }
  }
  if (best < 0)
    throw std::logic_error(std::string("synthesize_jump: no monotone root curve for the ") + phase);
  return best;
}

void plan_countermovement(const JumpSetting& s, Phases& p) {
  p.t_dip = 0.4;             // countermovement starts
  p.t_low = p.t_dip + 0.55;  // bottom of the crouch
  p.depth = s.leg * std::min(0.18 + 0.2 * s.height, 0.3);
  p.y_low = s.y_stand - p.depth;
}

void plan_push_off(const JumpSetting& s, const Flight& fl, Phases& p) {
  const double push = gentlest_duration("push-off", p.y_low, 0, 0, fl.root_off.y(), s.vy, -s.g);
  p.z_low = std::min(s.z_stand - 0.3 * p.depth, fl.root_off.z() - 0.5 * fl.vz * push);
  p.t_off = p.t_low + push;
  p.t_heel = p.t_low + 0.3 * push;  // heels rise
  p.off_rate = 2 * kOffPitch / (p.t_off - p.t_heel);
}

void plan_flight(const Flight& fl, Phases& p) {
  p.t_land = p.t_off + fl.flight;
  p.t_tuck = p.t_off + 0.45 * fl.flight;
  p.t_reach = p.t_land - fl.reach_time;
}

// The landing crouch stops the fall over about v^2 / (3 g) (a mean deceleration of 1.5 g), at
// least as deep as depth_land below standing, but with the legs at least 0.55 of their length.
void plan_landing(const JumpSetting& s, const Flight& fl, Phases& p) {
  const double depth_land = s.leg * std::min(0.16 + 0.2 * s.height, 0.3);
  p.y_absorb = std::max(std::min({s.y_stand - depth_land, fl.root_land.y() - 0.1 * s.leg,
                                  fl.root_land.y() - fl.v_land * fl.v_land / (3 * s.g)}),
                        s.fig.dims.ankle_height + 0.55 * s.leg);
  const double absorb = gentlest_duration("landing", fl.root_land.y(), fl.v_land, -s.g, p.y_absorb, 0, 0);
  p.z_absorb = fl.root_land.z() + 0.5 * fl.vz * absorb;
  p.t_absorbed = p.t_land + absorb;
}

void plan_recovery(Phases& p) {
  p.t_stood = p.t_absorbed + 0.7;
  p.end = p.t_stood + 0.5;
}

Phases plan_phases(const JumpSetting& s, const Flight& fl) {
  Phases p;
  plan_countermovement(s, p);
  plan_push_off(s, fl, p);
  plan_flight(fl, p);
  plan_landing(s, fl, p);
  plan_recovery(p);
  return p;
}

struct RootCurves {
  Curve y, z;
};

// Root: quintics in the ground phases matching the flight's position, velocity and -g.
RootCurves root_curves(const JumpSetting& s, const Flight& fl, const Phases& p) {
  RootCurves r;
  r.y.add_hold(0, p.t_dip, s.y_stand);
  r.y.add_quintic(p.t_dip, p.t_low, s.y_stand, 0, 0, p.y_low, 0, 0);
  r.y.add_quintic(p.t_low, p.t_off, p.y_low, 0, 0, fl.root_off.y(), s.vy, -s.g);
  r.y.add_poly(p.t_off, p.t_land, {fl.root_off.y(), s.vy, -s.g / 2, 0, 0, 0});
  r.y.add_quintic(p.t_land, p.t_absorbed, fl.root_land.y(), fl.v_land, -s.g, p.y_absorb, 0, 0);
  r.y.add_quintic(p.t_absorbed, p.t_stood, p.y_absorb, 0, 0, s.y_stand, 0, 0);
  r.y.add_hold(p.t_stood, p.end, s.y_stand);
  r.z.add_hold(0, p.t_dip, s.z_stand);
  r.z.add_quintic(p.t_dip, p.t_low, s.z_stand, 0, 0, p.z_low, 0, 0);
  r.z.add_quintic(p.t_low, p.t_off, p.z_low, 0, 0, fl.root_off.z(), fl.vz, 0);
  r.z.add_poly(p.t_off, p.t_land, {fl.root_off.z(), fl.vz, 0, 0, 0, 0});
  r.z.add_quintic(p.t_land, p.t_absorbed, fl.root_land.z(), fl.vz, 0, p.z_absorb, 0, 0);
  r.z.add_quintic(p.t_absorbed, p.t_stood, p.z_absorb, 0, 0, s.z_stand + s.distance, 0, 0);
  r.z.add_hold(p.t_stood, p.end, s.z_stand + s.distance);
  return r;
}

struct UpperBody {
  Curve pelvis_pitch, spine_flex, arm_flex, elbow;
};

// Upper body: the trunk folds into the crouches, the arms swing back in the countermovement and
// forward-up through the push-off.
UpperBody upper_body_curves(const Flight& fl, const Phases& p) {
  return {.pelvis_pitch = monotone_curve({{p.t_dip, kTiltStand},
                                          {p.t_low, 0.45},
                                          {p.t_off, fl.pitch_off},
                                          {p.t_tuck, 0.35},
                                          {p.t_land, kPitchLand},
                                          {p.t_absorbed, 0.45},
                                          {p.t_stood, kTiltStand}}),
          .spine_flex = monotone_curve({{p.t_dip, 0},
                                        {p.t_low, 0.25},
                                        {p.t_off, 0.05},
                                        {p.t_tuck, 0.25},
                                        {p.t_land, 0.15},
                                        {p.t_absorbed, 0.3},
                                        {p.t_stood, 0}}),
          .arm_flex = monotone_curve({{p.t_dip, 0},
                                      {p.t_low, -0.9},
                                      {p.t_off, 2.3},
                                      {p.t_tuck, 1.9},
                                      {p.t_land, 1.3},
                                      {p.t_absorbed, 0.9},
                                      {p.t_stood, 0}}),
          .elbow = monotone_curve({{p.t_dip, 0.1},
                                   {p.t_low, 0.25},
                                   {p.t_off, 0.15},
                                   {p.t_tuck, 0.3},
                                   {p.t_land, 0.35},
                                   {p.t_absorbed, 0.5},
                                   {p.t_stood, 0.1}})};
}

// A foot in flight at time t: its ball joint relative to the root, its pitch and its toe's pitch
// relative to it, each with its rate.
struct FlightKey {
  double t;
  Eigen::Vector3d ball_rel, ball_rel_rate;
  double pitch, pitch_rate, toe_rel, toe_rel_rate;
};
using FlightKeys = std::array<std::array<FlightKey, 5>, 2>;  // per side

// Feet in flight, on Hermite pieces between keys continuing the ground phases' rates (so the ball
// leaves and lands at rest, and the ankle's velocity is continuous). The feet leave at rest and
// catch up with the hips within catch_up seconds (having covered half the hips' travel
// meanwhile: the legs extend a little further), are tucked up under the hips at t_tuck, reach for
// the floor at t_reach.
FlightKeys flight_keys(const JumpSetting& s, const Flight& fl, const Phases& p, const Curve& pelvis_pitch) {
  const double catch_up = std::min(0.04, 0.15 * fl.flight);
  const double t_catch = p.t_off + catch_up;
  const Eigen::Vector3d root_rate_off(0, s.vy, fl.vz);
  const Eigen::Vector3d root_catch =
      fl.root_off + root_rate_off * catch_up - Eigen::Vector3d(0, s.g * catch_up * catch_up / 2, 0);
  const Eigen::Vector3d ball_rel_catch = s.ball_start[kLeft] + root_rate_off * (catch_up / 2) - root_catch;
  const double catch_pitch = kOffPitch + p.off_rate * catch_up / 2;
  FlightKeys keys;
  for (Side side : {kLeft, kRight}) {
    const Eigen::Vector3d mirror(side_sign(side), 1, 1);
    const Eigen::Vector3d hip_rel_tuck = rot_x(pelvis_pitch.value(p.t_tuck)) * s.hip_offset;
    const Eigen::Vector3d ankle_rel_tuck = ankle_from_hip(s, hip_rel_tuck, 0.6, 0.05, s.foot_x);
    const Eigen::Vector3d ball_rel_tuck =
        ankle_rel_tuck + rot_y(s.yaw[kLeft]) * (rot_x(kTuckPitch) * s.geo.ball_offset());
    const Eigen::Vector3d off_rate_v(0, -s.vy, -fl.vz), land_rate_v(0, -fl.v_land, -fl.vz);
    keys[side] = {
        FlightKey{p.t_off, fl.ball_rel_off.cwiseProduct(mirror), off_rate_v, kOffPitch, p.off_rate,
                  -kOffPitch, -p.off_rate},
        FlightKey{t_catch, ball_rel_catch.cwiseProduct(mirror), Eigen::Vector3d::Zero(), catch_pitch, 0,
                  -catch_pitch, 0},
        FlightKey{p.t_tuck, ball_rel_tuck.cwiseProduct(mirror), Eigen::Vector3d::Zero(), kTuckPitch, 0, 0, 0},
        FlightKey{p.t_reach, fl.ball_rel_reach.cwiseProduct(mirror), Eigen::Vector3d::Zero(), fl.reach_pitch,
                  0, -fl.reach_pitch, 0},
        FlightKey{p.t_land, fl.ball_rel_land.cwiseProduct(mirror), land_rate_v, kLandPitch, kLandingRate,
                  -kLandPitch, -kLandingRate}};
  }
  return keys;
}

// Everything of a jump plan that frames and plants need.
struct JumpPlan {
  const JumpSetting& setting;
  Flight flight;
  Phases phases;
  RootCurves root;
  UpperBody upper;
  FlightKeys feet;
};

// Plans the jump with the legs at `takeoff_extension` of their length at takeoff.
JumpPlan plan_jump(const JumpSetting& s, double takeoff_extension) {
  const Flight flight = solve_flight(s, takeoff_extension);
  const Phases phases = plan_phases(s, flight);
  RootCurves root = root_curves(s, flight, phases);
  UpperBody upper = upper_body_curves(flight, phases);
  FlightKeys feet = flight_keys(s, flight, phases, upper.pelvis_pitch);
  return {s, flight, phases, std::move(root), std::move(upper), feet};
}

// On the floor the foot rolls about its ball: before takeoff its heel rises, after touchdown it
// comes down.
FootState foot_on_floor(const JumpPlan& plan, Side side, double t) {
  const JumpSetting& s = plan.setting;
  const Phases& p = plan.phases;
  FootState f;
  f.yaw = s.yaw[side];
  if (t <= p.t_off) {
    if (t > p.t_heel) {
      const double h = p.t_off - p.t_heel;
      f.pitch = hermite(0, 0, kOffPitch, p.off_rate, h, (t - p.t_heel) / h);
    }
    f.ankle = s.geo.ankle_about(s.ball_start[side], s.geo.ball_offset(), f.yaw, f.pitch);
    return f;
  }
  if (t < p.t_land + kHeelDrop)
    f.pitch = hermite(kLandPitch, kLandingRate, 0, 0, kHeelDrop, (t - p.t_land) / kHeelDrop);
  f.ankle = s.geo.ankle_about(s.ball_land[side], s.geo.ball_offset(), f.yaw, f.pitch);
  return f;
}

FootState foot_at(const JumpPlan& plan, Side side, double t, const Eigen::Vector3d& root) {
  if (t <= plan.phases.t_off || t >= plan.phases.t_land) return foot_on_floor(plan, side, t);
  const JumpSetting& s = plan.setting;
  FootState f;
  f.yaw = s.yaw[side];
  const auto& keys = plan.feet[side];
  std::size_t i = 0;
  while (i + 2 < keys.size() && t > keys[i + 1].t) ++i;
  const FlightKey& a = keys[i];
  const FlightKey& b = keys[i + 1];
  const double h = b.t - a.t, u = (t - a.t) / h;
  const Eigen::Vector3d ball = root + hermite(a.ball_rel, a.ball_rel_rate, b.ball_rel, b.ball_rel_rate, h, u);
  f.pitch = hermite(a.pitch, a.pitch_rate, b.pitch, b.pitch_rate, h, u);
  f.toe_pitch = f.pitch + hermite(a.toe_rel, a.toe_rel_rate, b.toe_rel, b.toe_rel_rate, h, u);
  f.ankle = s.geo.ankle_about(ball, s.geo.ball_offset(), f.yaw, f.pitch);
  return f;
}

BodyPose planned_pose(const JumpPlan& plan, double t) {
  const UpperBody& upper = plan.upper;
  BodyPose p;
  p.root = Eigen::Vector3d(0, plan.root.y.value(t), plan.root.z.value(t));
  const double pitch = upper.pelvis_pitch.value(t);
  p.pelvis = rot_x(pitch);
  p.chest = rot_x(pitch + upper.spine_flex.value(t));
  p.head = rot_x(0.3 * (pitch + upper.spine_flex.value(t)));
  for (Side side : {kLeft, kRight}) {
    p.arms[side] = {0.12, upper.arm_flex.value(t), upper.elbow.value(t)};
    p.feet[side] = foot_at(plan, side, t, p.root);
  }
  return p;
}

// The highest takeoff extension (from 0.95 down) whose early flight keeps the legs within 0.99
// of their length: right after takeoff the hips fly on while the feet, leaving at rest, catch up.
JumpPlan plan_highest_takeoff(const JumpSetting& s, const PoseWriter& writer) {
  for (double takeoff_extension = 0.95;; takeoff_extension -= 0.01) {
    JumpPlan plan = plan_jump(s, takeoff_extension);
    double worst = 0;
    for (double t = plan.phases.t_off; t <= plan.phases.t_land; t += 1e-3) {
      const BodyPose p = planned_pose(plan, t);
      worst = std::max({worst, writer.leg_extension(p, kLeft), writer.leg_extension(p, kRight)});
    }
    if (worst <= 0.99) return plan;
    if (takeoff_extension < 0.8)
      throw std::logic_error("synthesize_jump: the legs cannot follow the planned jump");
  }
}

// The mass model of retime.body_model's default (de Leva's male table), as the retiming sees it.
body::BodyModel default_body_model(const Figure& fig) {
  const Eigen::RowVectorXd rest = body::rest_pose_values(*fig.skeleton);
  return body::build_body_model(fig.skeleton, {}, &rest).body;
}

// In flight the whole body, not the root, must fall freely: the limbs tuck and reach relative
// to the root, which moves the centre of mass about it. So the flying body is translated by
// the difference between the ballistic parabola through the centre of mass at takeoff and at
// touchdown and the centre of mass the plan gives (a rigid shift: legs and arms keep their
// joint angles). The shift fades in over the first `ramp` seconds of the flight and out over the
// last, without a kink: the feet leave and meet the floor at rest, and a shift changing at once
// would push them through it.
class BallisticFlight {
 public:
  BallisticFlight(const Figure& fig, const JumpPlan& plan)
      : plan_(plan),
        body_(default_body_model(fig)),
        com_writer_(fig),
        values_(fig.skeleton->channel_count()),
        t_off_(plan.phases.t_off),
        t_land_(plan.phases.t_land),
        down_(0, -plan.setting.g, 0) {
    const double flight_time = t_land_ - t_off_;
    com_off_ = com_of(planned_pose(plan, t_off_));
    const Eigen::Vector3d com_land = com_of(planned_pose(plan, t_land_));
    com_velocity_ = (com_land - com_off_ - 0.5 * down_ * flight_time * flight_time) / flight_time;
    ramp_ = std::min(0.04, 0.15 * flight_time);
  }

  BodyPose pose_at(double t) {
    BodyPose p = planned_pose(plan_, t);
    if (t <= t_off_ || t >= t_land_) return p;
    const double s = t - t_off_, edge = std::min(s, t_land_ - t) / ramp_;
    const double fade = edge >= 1 ? 1 : edge * edge * (3 - 2 * edge);
    const Eigen::Vector3d shift = fade * (com_off_ + com_velocity_ * s + 0.5 * down_ * s * s - com_of(p));
    p.root += shift;
    for (Side side : {kLeft, kRight}) p.feet[side].ankle += shift;
    return p;
  }

 private:
  Eigen::Vector3d com_of(const BodyPose& p) {
    com_writer_.write(p, values_.data());
    return body::body_com(body_, values_);
  }

  const JumpPlan& plan_;
  const body::BodyModel body_;
  // Its own writer: the frames' writer carries each joint's Euler branch from frame to frame.
  PoseWriter com_writer_;
  Eigen::RowVectorXd values_;
  double t_off_, t_land_;
  Eigen::Vector3d down_, com_off_, com_velocity_;
  double ramp_ = 0;
};

void record_plants(const JumpSetting& s, const Phases& p, double fps, int frames,
                   std::vector<FootPlant>& out) {
  const Figure& fig = s.fig;
  const double t_end = (frames - 1) / fps;
  PlantRecorder plants(fig, fps, frames, out);
  for (Side side : {kLeft, kRight}) {
    const Eigen::Matrix3d R = rot_y(s.yaw[side]);
    plants.add(side, FootPoint::Heel, 0, p.t_heel, s.geo.heel_when_flat(s.ankle_start[side], s.yaw[side]));
    plants.add(side, FootPoint::Ankle, 0, p.t_heel, s.ankle_start[side]);
    plants.add(side, FootPoint::Ball, 0, p.t_off, s.ball_start[side]);
    plants.add(side, FootPoint::Toe, 0, p.t_off, s.ball_start[side] + R * fig.toe_tip_local);
    plants.add(side, FootPoint::Heel, p.t_land + kHeelDrop, t_end,
               s.geo.heel_when_flat(s.ankle_land[side], s.yaw[side]));
    plants.add(side, FootPoint::Ankle, p.t_land + kHeelDrop, t_end, s.ankle_land[side]);
    plants.add(side, FootPoint::Ball, p.t_land, t_end, s.ball_land[side]);
    plants.add(side, FootPoint::Toe, p.t_land, t_end, s.ball_land[side] + R * fig.toe_tip_local);
  }
  std::stable_sort(out.begin(), out.end(), [](const FootPlant& a, const FootPlant& b) {
    if (a.side != b.side) return a.side < b.side;
    return a.first_frame < b.first_frame;
  });
}

}  // namespace

Synthesis synthesize_jump(const JumpOptions& options) {
  options.validate();
  Synthesis out;
  out.figure = make_figure(options.stature);
  PoseWriter writer(out.figure);
  const JumpSetting setting = place_feet(out.figure, options, writer);
  const JumpPlan plan = plan_highest_takeoff(setting, writer);
  BallisticFlight flight(out.figure, plan);

  const int frames = static_cast<int>(std::lround(plan.phases.end * options.fps)) + 1;
  out.max_leg_extension = write_frames(
      writer, out.figure, [&](double t) { return flight.pose_at(t); }, frames, options.fps, "synth_jump",
      out.motion);
  if (out.max_leg_extension > 0.999)
    throw std::logic_error("synthesize_jump: the legs cannot follow the planned jump");

  record_plants(setting, plan.phases, options.fps, frames, out.plants);
  out.flight_start = plan.phases.t_off;
  out.flight_end = plan.phases.t_land;
  out.takeoff_velocity_up = setting.vy;
  out.takeoff_velocity_forward = plan.flight.vz;
  out.gravity = options.gravity;
  return out;
}

}  // namespace kg::synth
