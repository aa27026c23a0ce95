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

Synthesis synthesize_jump(const JumpOptions& options) {
  check_range("jump", "height", options.height, kJumpHeightRange.min, kJumpHeightRange.max, "m");
  check_range("jump", "distance", options.distance, kJumpDistanceRange.min, kJumpDistanceRange.max, "m");
  check_range("jump", "stature", options.stature, kStatureRange.min, kStatureRange.max, "m");
  check_range("jump", "fps", options.fps, kFpsRange.min, kFpsRange.max, "frames/s");
  check_range("jump", "gravity", options.gravity, kGravityRange.min, kGravityRange.max, "m/s^2");

  Synthesis out;
  out.figure = make_figure(options.stature);
  const Figure& fig = out.figure;
  const FigureDimensions& dims = fig.dims;
  const double H = dims.stature, leg = dims.leg_length();
  const double g = options.gravity, jump_h = options.height, dist = options.distance;
  const FootGeometry geo(fig);
  PoseWriter writer(fig);

  // Feet: hip width apart, toes slightly out; they land `dist` further along +Z.
  const double foot_x = 0.055 * H, toe_out = 0.12;
  std::array<Eigen::Vector3d, 2> ankle_start, ball_start, ankle_land, ball_land;
  std::array<double, 2> yaw{};
  for (Side side : {kLeft, kRight}) {
    yaw[side] = side_sign(side) * toe_out;
    ankle_start[side] = Eigen::Vector3d(side_sign(side) * foot_x, dims.ankle_height, 0);
    ankle_land[side] = ankle_start[side] + Eigen::Vector3d(0, 0, dist);
    ball_start[side] = geo.ball_when_flat(ankle_start[side], yaw[side]);
    ball_land[side] = geo.ball_when_flat(ankle_land[side], yaw[side]);
  }
  const Eigen::Vector3d hip_offset =
      fig.skeleton->joint(fig.up_leg[kLeft]).offset;  // left; mirrored for right

  // Foot pitches (heel up) at takeoff, at the tuck and at touchdown; the heels come down in
  // heel_drop seconds after touchdown, starting at the rate landing_rate.
  const double off_pitch = 0.8, tuck_pitch = 0.3, land_pitch = 0.35, heel_drop = 0.12;
  const double landing_rate = -1.5 * land_pitch / heel_drop;

  // Standing root: legs at 0.996 of their length (as the walk's), hips a little ahead of the ankles.
  const double z_stand = 0.02 * H, tilt_stand = 0.03;
  auto standing_pose = [&](double z) {
    BodyPose p;
    p.root = Eigen::Vector3d(0, 0, z);
    p.pelvis = rot_x(tilt_stand);
    for (Side side : {kLeft, kRight}) p.feet[side] = {ankle_start[side], yaw[side], 0, 0};
    return p;
  };
  const double y_stand = root_height_for(writer, standing_pose(z_stand), 0.996, 0, H);

  // Everything of a jump plan that frames and plants need.
  struct Plan {
    double t_heel, t_off, t_land, end;
    double vy, vz;
    std::function<BodyPose(double)> pose;
  };
  // Plans the jump with the legs at `takeoff_extension` of their length at takeoff.
  auto plan_jump = [&](const double takeoff_extension) {
    // Takeoff and touchdown: the root's height and forward speed follow from the legs' geometry at
    // both instants, which leans with the forward speed vz. For a given vz, the landing geometry
    // and the flight time settle by fixed-point iteration (weakly coupled through the landing
    // speed); the vz the geometry implies falls as vz rises, so bisection finds the consistent one.
    const double vy = std::sqrt(2 * g * jump_h);
    const double pitch_land = 0.15;
    // The point of a leg `extension` long from the hip, leaning `lean` (forward positive) in the
    // sagittal plane (the ankle behind the hip for lean > 0), with the hip at hip_rel from the root
    // and the ankle at sideways position ankle_x: the ankle relative to the root.
    auto ankle_from_hip = [&](const Eigen::Vector3d& hip_rel, double extension, double lean, double ankle_x) {
      const double dx = ankle_x - hip_rel.x();
      const double r = std::sqrt(std::pow(extension * leg, 2) - dx * dx);
      return Eigen::Vector3d(hip_rel.x() + dx, hip_rel.y() - r * std::cos(lean),
                             hip_rel.z() - r * std::sin(lean));
    };
    struct Flight {
      double vz = 0, v_land = 0, flight = 0, reach_time = 0, reach_pitch = 0, lean_off = 0, pitch_off = 0;
      Eigen::Vector3d root_off, root_land, ball_rel_off, ball_rel_reach, ball_rel_land;
      double implied_vz = 0;
    };
    auto flight_for = [&](double vz) {
      Flight f;
      f.vz = vz;
      f.lean_off = 0.55 * std::atan2(vz, vy);
      f.pitch_off = 0.05 + 0.5 * f.lean_off;
      // Takeoff: the ball on the floor, the foot pitched off_pitch, the leg leaning forward.
      const Eigen::Vector3d ankle_off =
          geo.ankle_about(ball_start[kLeft], geo.ball_offset(), yaw[kLeft], off_pitch);
      const Eigen::Vector3d hip_rel_off = rot_x(f.pitch_off) * hip_offset;
      f.root_off = ankle_off - ankle_from_hip(hip_rel_off, takeoff_extension, f.lean_off, ankle_off.x());
      f.root_off.x() = 0;
      f.ball_rel_off = ball_start[kLeft] - f.root_off;
      // Touchdown: reach_time before it the leg reaches `extension` long, feet ahead; then the foot
      // decelerates to rest while the root keeps falling, so relative to the root it rises and
      // draws back. The landing root height for a reach of `extension`:
      auto land = [&](double extension) {
        const double lean_land = -0.45 * std::atan2(vz, std::abs(f.v_land));
        const Eigen::Vector3d hip_rel_land = rot_x(pitch_land) * hip_offset;
        f.ball_rel_reach = ankle_from_hip(hip_rel_land, extension, lean_land, foot_x) +
                           rot_y(yaw[kLeft]) * (rot_x(f.reach_pitch) * geo.ball_offset());
        f.ball_rel_reach.x() =
            ball_land[kLeft].x();  // the root flies at x = 0: no sideways jump at touchdown
        f.ball_rel_land = f.ball_rel_reach + Eigen::Vector3d(0, std::abs(f.v_land) * f.reach_time / 2.5,
                                                             -vz * f.reach_time / 2.5);
        f.root_land = ball_land[kLeft] - f.ball_rel_land;
        f.root_land.x() = 0;
      };
      f.v_land = -vy;
      f.flight = 2 * vy / g;
      for (int iter = 0; iter < 100; ++iter) {
        f.reach_time = std::min(0.08, 0.2 * f.flight);
        f.reach_pitch = land_pitch + std::abs(landing_rate) * f.reach_time / 2.5;
        land(0.96);
        // A low hop lands no higher than half way up to its apex: the legs reach less far.
        const double ceiling = f.root_off.y() + 0.5 * jump_h;
        if (f.root_land.y() > ceiling) {
          double lo = 0.5, hi = 0.96;
          for (int i = 0; i < 50; ++i) {
            land((lo + hi) / 2);
            (f.root_land.y() > ceiling ? hi : lo) = (lo + hi) / 2;
          }
          land(lo);
        }
        const double drop = f.root_off.y() - f.root_land.y();
        const double flight = (vy + std::sqrt(vy * vy + 2 * g * drop)) / g;
        const bool settled = std::abs(flight - f.flight) < 1e-14;
        f.flight = flight;
        f.v_land = vy - g * flight;
        if (settled) break;
      }
      f.implied_vz = (f.root_land.z() - f.root_off.z()) / f.flight;
      return f;
    };
    double vz_lo = -3, vz_hi = 3 * vy + 1;
    for (int i = 0; i < 80; ++i) {
      const double mid = (vz_lo + vz_hi) / 2;
      (flight_for(mid).implied_vz > mid ? vz_lo : vz_hi) = mid;
    }
    const Flight fl = flight_for((vz_lo + vz_hi) / 2);
    // Standing long jumps leave at 30-45 degrees; flatter than about 27 (forward speed over twice
    // the upward one) is no standing jump this figure can do.
    if (fl.vz > 2 * vy) {
      std::ostringstream msg;
      msg << "synthesize_jump: distance " << dist << " m with height " << jump_h
          << " m needs a forward takeoff speed of " << (fl.vz < vz_hi - 1e-6 ? "" : "over ") << fl.vz
          << " m/s, more than twice the upward " << vy << " m/s: raise the height or shorten the distance";
      throw std::invalid_argument(msg.str());
    }
    const double vz = fl.vz, v_land = fl.v_land, flight = fl.flight, reach_time = fl.reach_time;
    const double reach_pitch = fl.reach_pitch, pitch_off = fl.pitch_off;
    const Eigen::Vector3d root_off = fl.root_off, root_land = fl.root_land, ball_rel_off = fl.ball_rel_off;
    const Eigen::Vector3d ball_rel_reach = fl.ball_rel_reach, ball_rel_land = fl.ball_rel_land;

    // Timeline.
    const double t_dip = 0.4;           // countermovement starts
    const double t_low = t_dip + 0.55;  // bottom of the crouch
    const double depth = leg * std::min(0.18 + 0.2 * jump_h, 0.3);
    const double y_low = y_stand - depth;
    // Durations of the push-off and of the absorbing crouch: among the quintics moving the root one
    // way only (the hips neither dip before rising nor bounce at the bottom), the one of least peak
    // acceleration.
    auto gentlest_duration = [](const char* phase, double y0, double v0, double a0, double y1, double v1,
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
    };
    const double push = gentlest_duration("push-off", y_low, 0, 0, root_off.y(), vy, -g);
    const double z_low = std::min(z_stand - 0.3 * depth, root_off.z() - 0.5 * vz * push);
    const double t_off = t_low + push;
    const double t_heel = t_low + 0.3 * push;  // heels rise
    const double off_rate = 2 * off_pitch / (t_off - t_heel);
    const double t_land = t_off + flight;
    const double t_tuck = t_off + 0.45 * flight;
    const double t_reach = t_land - reach_time;
    const double depth_land = leg * std::min(0.16 + 0.2 * jump_h, 0.3);
    // The landing crouch stops the fall over about v^2 / (3 g) (a mean deceleration of 1.5 g), at
    // least as deep as depth_land below standing, but with the legs at least 0.55 of their length.
    const double y_absorb = std::max(std::min({y_stand - depth_land, root_land.y() - 0.1 * leg,
                                               root_land.y() - v_land * v_land / (3 * g)}),
                                     dims.ankle_height + 0.55 * leg);
    const double absorb = gentlest_duration("landing", root_land.y(), v_land, -g, y_absorb, 0, 0);
    const double z_absorb = root_land.z() + 0.5 * vz * absorb;
    const double t_absorbed = t_land + absorb;
    const double t_stood = t_absorbed + 0.7;
    const double end = t_stood + 0.5;

    // Root: quintics in the ground phases matching the flight's position, velocity and -g.
    Curve ry, rz;
    ry.add_hold(0, t_dip, y_stand);
    ry.add_quintic(t_dip, t_low, y_stand, 0, 0, y_low, 0, 0);
    ry.add_quintic(t_low, t_off, y_low, 0, 0, root_off.y(), vy, -g);
    ry.add_poly(t_off, t_land, {root_off.y(), vy, -g / 2, 0, 0, 0});
    ry.add_quintic(t_land, t_absorbed, root_land.y(), v_land, -g, y_absorb, 0, 0);
    ry.add_quintic(t_absorbed, t_stood, y_absorb, 0, 0, y_stand, 0, 0);
    ry.add_hold(t_stood, end, y_stand);
    rz.add_hold(0, t_dip, z_stand);
    rz.add_quintic(t_dip, t_low, z_stand, 0, 0, z_low, 0, 0);
    rz.add_quintic(t_low, t_off, z_low, 0, 0, root_off.z(), vz, 0);
    rz.add_poly(t_off, t_land, {root_off.z(), vz, 0, 0, 0, 0});
    rz.add_quintic(t_land, t_absorbed, root_land.z(), vz, 0, z_absorb, 0, 0);
    rz.add_quintic(t_absorbed, t_stood, z_absorb, 0, 0, z_stand + dist, 0, 0);
    rz.add_hold(t_stood, end, z_stand + dist);

    // Upper body: the trunk folds into the crouches, the arms swing back in the countermovement and
    // forward-up through the push-off.
    const Curve pelvis_pitch = monotone_curve({{t_dip, tilt_stand},
                                               {t_low, 0.45},
                                               {t_off, pitch_off},
                                               {t_tuck, 0.35},
                                               {t_land, pitch_land},
                                               {t_absorbed, 0.45},
                                               {t_stood, tilt_stand}});
    const Curve spine_flex = monotone_curve({{t_dip, 0},
                                             {t_low, 0.25},
                                             {t_off, 0.05},
                                             {t_tuck, 0.25},
                                             {t_land, 0.15},
                                             {t_absorbed, 0.3},
                                             {t_stood, 0}});
    const Curve arm_flex = monotone_curve({{t_dip, 0},
                                           {t_low, -0.9},
                                           {t_off, 2.3},
                                           {t_tuck, 1.9},
                                           {t_land, 1.3},
                                           {t_absorbed, 0.9},
                                           {t_stood, 0}});
    const Curve elbow = monotone_curve({{t_dip, 0.1},
                                        {t_low, 0.25},
                                        {t_off, 0.15},
                                        {t_tuck, 0.3},
                                        {t_land, 0.35},
                                        {t_absorbed, 0.5},
                                        {t_stood, 0.1}});

    // Feet in flight: the ball joint relative to the root, and the foot and toe pitches, on Hermite
    // pieces continuing the ground phases' rates (so the ball leaves and lands at rest, and the
    // ankle's velocity is continuous). The feet leave at rest and catch up with the hips within
    // catch_up seconds (having covered half the hips' travel meanwhile: the legs extend a little
    // further), are tucked up under the hips at t_tuck, reach for the floor at t_reach.
    struct Key {
      double t;
      Eigen::Vector3d ball_rel, ball_rel_rate;
      double pitch, pitch_rate, toe_rel, toe_rel_rate;
    };
    const double catch_up = std::min(0.04, 0.15 * flight);
    const double t_catch = t_off + catch_up;
    const Eigen::Vector3d root_rate_off(0, vy, vz);
    const Eigen::Vector3d root_catch =
        root_off + root_rate_off * catch_up - Eigen::Vector3d(0, g * catch_up * catch_up / 2, 0);
    const Eigen::Vector3d ball_rel_catch = ball_start[kLeft] + root_rate_off * (catch_up / 2) - root_catch;
    const double catch_pitch = off_pitch + off_rate * catch_up / 2;
    std::array<std::array<Key, 5>, 2> flight_keys;
    for (Side side : {kLeft, kRight}) {
      const Eigen::Vector3d mirror(side_sign(side), 1, 1);
      const Eigen::Vector3d hip_rel_tuck = rot_x(pelvis_pitch.value(t_tuck)) * hip_offset;
      const Eigen::Vector3d ankle_rel_tuck = ankle_from_hip(hip_rel_tuck, 0.6, 0.05, foot_x);
      const Eigen::Vector3d ball_rel_tuck =
          ankle_rel_tuck + rot_y(yaw[kLeft]) * (rot_x(tuck_pitch) * geo.ball_offset());
      const Eigen::Vector3d off_rate_v(0, -vy, -vz), land_rate_v(0, -v_land, -vz);
      flight_keys[side] = {
          Key{t_off, ball_rel_off.cwiseProduct(mirror), off_rate_v, off_pitch, off_rate, -off_pitch,
              -off_rate},
          Key{t_catch, ball_rel_catch.cwiseProduct(mirror), Eigen::Vector3d::Zero(), catch_pitch, 0,
              -catch_pitch, 0},
          Key{t_tuck, ball_rel_tuck.cwiseProduct(mirror), Eigen::Vector3d::Zero(), tuck_pitch, 0, 0, 0},
          Key{t_reach, ball_rel_reach.cwiseProduct(mirror), Eigen::Vector3d::Zero(), reach_pitch, 0,
              -reach_pitch, 0},
          Key{t_land, ball_rel_land.cwiseProduct(mirror), land_rate_v, land_pitch, landing_rate, -land_pitch,
              -landing_rate}};
    }

    auto foot_at = [=](Side side, double t, const Eigen::Vector3d& root) {
      FootState f;
      f.yaw = yaw[side];
      if (t <= t_off) {
        if (t > t_heel) {
          const double h = t_off - t_heel;
          f.pitch = hermite(0, 0, off_pitch, off_rate, h, (t - t_heel) / h);
        }
        f.ankle = geo.ankle_about(ball_start[side], geo.ball_offset(), f.yaw, f.pitch);
        return f;
      }
      if (t >= t_land) {
        if (t < t_land + heel_drop)
          f.pitch = hermite(land_pitch, landing_rate, 0, 0, heel_drop, (t - t_land) / heel_drop);
        f.ankle = geo.ankle_about(ball_land[side], geo.ball_offset(), f.yaw, f.pitch);
        return f;
      }
      const auto& keys = flight_keys[side];
      std::size_t i = 0;
      while (i + 2 < keys.size() && t > keys[i + 1].t) ++i;
      const Key& a = keys[i];
      const Key& b = keys[i + 1];
      const double h = b.t - a.t, s = (t - a.t) / h;
      const Eigen::Vector3d ball =
          root + hermite(a.ball_rel, a.ball_rel_rate, b.ball_rel, b.ball_rel_rate, h, s);
      f.pitch = hermite(a.pitch, a.pitch_rate, b.pitch, b.pitch_rate, h, s);
      f.toe_pitch = f.pitch + hermite(a.toe_rel, a.toe_rel_rate, b.toe_rel, b.toe_rel_rate, h, s);
      f.ankle = geo.ankle_about(ball, geo.ball_offset(), f.yaw, f.pitch);
      return f;
    };

    Plan plan;
    plan.t_heel = t_heel;
    plan.t_off = t_off;
    plan.t_land = t_land;
    plan.end = end;
    plan.vy = vy;
    plan.vz = vz;
    plan.pose = [=](double t) {
      BodyPose p;
      p.root = Eigen::Vector3d(0, ry.value(t), rz.value(t));
      const double pitch = pelvis_pitch.value(t);
      p.pelvis = rot_x(pitch);
      p.chest = rot_x(pitch + spine_flex.value(t));
      p.head = rot_x(0.3 * (pitch + spine_flex.value(t)));
      for (Side side : {kLeft, kRight}) {
        p.arms[side] = {0.12, arm_flex.value(t), elbow.value(t)};
        p.feet[side] = foot_at(side, t, p.root);
      }
      return p;
    };
    return plan;
  };

  // The highest takeoff extension (from 0.95 down) whose early flight keeps the legs within 0.99
  // of their length: right after takeoff the hips fly on while the feet, leaving at rest, catch up.
  Plan plan;
  for (double takeoff_extension = 0.95;; takeoff_extension -= 0.01) {
    plan = plan_jump(takeoff_extension);
    double worst = 0;
    for (double t = plan.t_off; t <= plan.t_land; t += 1e-3) {
      const BodyPose p = plan.pose(t);
      worst = std::max({worst, writer.leg_extension(p, kLeft), writer.leg_extension(p, kRight)});
    }
    if (worst <= 0.99) break;
    if (takeoff_extension < 0.8)
      throw std::logic_error("synthesize_jump: the legs cannot follow the planned jump");
  }
  const double t_heel = plan.t_heel, t_off = plan.t_off, t_land = plan.t_land, end = plan.end;

  // In flight the whole body, not the root, must fall freely: the limbs tuck and reach relative
  // to the root, which moves the centre of mass about it. So the flying body is translated by
  // the difference between the ballistic parabola through the centre of mass at takeoff and at
  // touchdown and the centre of mass the plan gives (a rigid shift: legs and arms keep their
  // joint angles). The shift fades in over the first `ramp` seconds of the flight and out over the
  // last, without a kink: the feet leave and meet the floor at rest, and a shift changing at once
  // would push them through it. The mass model is retime.body_model's default (de Leva's male
  // table), as the retiming sees it.
  const body::BodyModel body = [&] {
    const Eigen::RowVectorXd rest = body::rest_pose_values(*fig.skeleton);
    return body::build_body_model(fig.skeleton, {}, &rest).body;
  }();
  // Its own writer: the frames' writer carries each joint's Euler branch from frame to frame.
  PoseWriter com_writer(fig);
  Eigen::RowVectorXd values(fig.skeleton->channel_count());
  auto com_of = [&](const BodyPose& p) {
    com_writer.write(p, values.data());
    return body::body_com(body, values);
  };
  const double flight_time = t_land - t_off;
  const Eigen::Vector3d com_off = com_of(plan.pose(t_off)), com_land = com_of(plan.pose(t_land));
  const Eigen::Vector3d down(0, -g, 0);
  const Eigen::Vector3d com_velocity =
      (com_land - com_off - 0.5 * down * flight_time * flight_time) / flight_time;
  const double ramp = std::min(0.04, 0.15 * flight_time);
  auto pose_at = [&](double t) {
    BodyPose p = plan.pose(t);
    if (t <= t_off || t >= t_land) return p;
    const double s = t - t_off, edge = std::min(s, t_land - t) / ramp;
    const double fade = edge >= 1 ? 1 : edge * edge * (3 - 2 * edge);
    const Eigen::Vector3d shift = fade * (com_off + com_velocity * s + 0.5 * down * s * s - com_of(p));
    p.root += shift;
    for (Side side : {kLeft, kRight}) p.feet[side].ankle += shift;
    return p;
  };

  const int frames = static_cast<int>(std::lround(end * options.fps)) + 1;
  out.max_leg_extension = write_frames(writer, fig, pose_at, frames, options.fps, "synth_jump", out.motion);
  if (out.max_leg_extension > 0.999)
    throw std::logic_error("synthesize_jump: the legs cannot follow the planned jump");

  const double t_end = (frames - 1) / options.fps;
  PlantRecorder plants(fig, options.fps, frames, out.plants);
  for (Side side : {kLeft, kRight}) {
    const Eigen::Matrix3d R = rot_y(yaw[side]);
    plants.add(side, FootPoint::Heel, 0, t_heel, geo.heel_when_flat(ankle_start[side], yaw[side]));
    plants.add(side, FootPoint::Ankle, 0, t_heel, ankle_start[side]);
    plants.add(side, FootPoint::Ball, 0, t_off, ball_start[side]);
    plants.add(side, FootPoint::Toe, 0, t_off, ball_start[side] + R * fig.toe_tip_local);
    plants.add(side, FootPoint::Heel, t_land + heel_drop, t_end,
               geo.heel_when_flat(ankle_land[side], yaw[side]));
    plants.add(side, FootPoint::Ankle, t_land + heel_drop, t_end, ankle_land[side]);
    plants.add(side, FootPoint::Ball, t_land, t_end, ball_land[side]);
    plants.add(side, FootPoint::Toe, t_land, t_end, ball_land[side] + R * fig.toe_tip_local);
  }
  std::stable_sort(out.plants.begin(), out.plants.end(), [](const FootPlant& a, const FootPlant& b) {
    if (a.side != b.side) return a.side < b.side;
    return a.first_frame < b.first_frame;
  });
  out.flight_start = t_off;
  out.flight_end = t_land;
  out.takeoff_velocity_up = plan.vy;
  out.takeoff_velocity_forward = plan.vz;
  out.gravity = g;
  return out;
}

}  // namespace kg::synth
