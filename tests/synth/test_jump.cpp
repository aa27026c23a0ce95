#include <catch2/catch.hpp>

#include <cmath>

#include "kg/body/body_build.hpp"
#include "synth_test_util.hpp"

using namespace kg;
using namespace kg::synth;
using namespace kg::synth::test;

namespace {

const Synthesis& default_jump() {
  static const Synthesis s = synthesize_jump({});
  return s;
}

// Frames strictly inside the flight (a second difference centred on f uses f - 1 and f + 1).
std::pair<int, int> flight_frames(const Synthesis& s) {
  const double fps = s.motion.fps;
  return {int(std::floor(s.flight_start * fps)) + 1, int(std::ceil(s.flight_end * fps)) - 1};
}

}  // namespace

TEST_CASE("jump: the body's centre of mass flies exactly ballistically", "[synth][jump]") {
  for (const JumpOptions& o : {JumpOptions{}, JumpOptions{.height = 0.5, .distance = 1.6},
                               JumpOptions{.height = 0.2, .distance = 0, .fps = 240},
                               JumpOptions{.height = 0.3, .distance = 0.5, .gravity = 3.71}}) {
    CAPTURE(o.height, o.distance, o.fps, o.gravity);
    const Synthesis s = synthesize_jump(o);
    const Kinematics k(s.motion);
    // The mass model the synthesizer and retime.body_model share by default (de Leva, male).
    const Eigen::RowVectorXd rest = body::rest_pose_values(*s.motion.skeleton);
    const body::BodyModel body = body::build_body_model(s.motion.skeleton, {}, &rest).body;
    auto com = [&](int f) { return body::body_com(body, s.motion.values.row(f)); };
    // The shift that makes it so fades in and out within 15% of the flight at either end.
    const double fps = s.motion.fps, flight = s.flight_end - s.flight_start;
    const int f0 = int(std::ceil((s.flight_start + 0.15 * flight) * fps)) + 1;
    const int f1 = int(std::floor((s.flight_end - 0.15 * flight) * fps)) - 1;
    REQUIRE(f1 - f0 > 10);
    const double dt = 1 / fps;
    double worst_rel = 0, worst_horizontal = 0, root_worst = 0;
    for (int f = f0; f <= f1; ++f) {
      const Eigen::Vector3d a = (com(f + 1) - 2 * com(f) + com(f - 1)) / (dt * dt);
      worst_rel = std::max(worst_rel, std::abs(a.y() + o.gravity) / o.gravity);
      worst_horizontal = std::max({worst_horizontal, std::abs(a.x()), std::abs(a.z())});
      const double root_ay = (k.joint(f + 1, s.figure.hips).y() - 2 * k.joint(f, s.figure.hips).y() +
                              k.joint(f - 1, s.figure.hips).y()) /
                             (dt * dt);
      root_worst = std::max(root_worst, std::abs(root_ay + o.gravity));
    }
    INFO("centre of mass: vertical acceleration off -g by at most "
         << worst_rel << " (relative); horizontal " << worst_horizontal << " m/s^2; the root's off -g by "
         << root_worst << " m/s^2");
    CHECK(worst_rel < 1e-6);
    CHECK(worst_horizontal < 1e-6 * o.gravity);
    // The root is not ballistic: the limbs tuck and reach about it.
    CHECK(root_worst > 0.05 * o.gravity);
    CHECK(s.takeoff_velocity_up == Approx(std::sqrt(2 * o.gravity * o.height)));
    // Both feet off the floor all through the flight, well clear at its middle.
    const auto [g0, g1] = flight_frames(s);
    double lowest = 1e9;
    for (int f = g0; f <= g1; ++f)
      for (Side side : {kLeft, kRight}) lowest = std::min(lowest, sole(k, s.figure, f, side).lowest());
    CHECK(lowest > 0);
    const int mid = (g0 + g1) / 2;
    for (Side side : {kLeft, kRight}) CHECK(sole(k, s.figure, mid, side).lowest() > 0.1);
  }
}

TEST_CASE("jump: feet planted exactly before takeoff and after landing, never through the floor",
          "[synth][jump]") {
  for (const JumpOptions& o :
       {JumpOptions{}, JumpOptions{.height = 0.6, .distance = 2.0},
        JumpOptions{.height = 0.05, .distance = 0}, JumpOptions{.stature = 1.2, .fps = 60},
        JumpOptions{.height = 0.4, .distance = 1.0, .stature = 2.2}}) {
    CAPTURE(o.height, o.distance, o.stature, o.fps);
    const Synthesis s = synthesize_jump(o);
    const Kinematics k(s.motion);
    const PlantErrors e = plant_errors(s, k);
    INFO("max drift " << e.drift << " m, height error " << e.height << " m, lowest sole "
                      << lowest_sole(s, k));
    CHECK(e.drift < 1e-6);
    CHECK(e.height < 1e-6);
    CHECK(lowest_sole(s, k) > -1e-9);
    CHECK(s.max_leg_extension < 0.999);
    // Both feet: planted from the start until takeoff, and from landing to the end.
    const int last = s.motion.frame_count() - 1;
    int before = 0, after = 0;
    for (const FootPlant& p : s.plants) {
      if (p.point != FootPoint::Toe) continue;
      if (p.first_frame == 0) {
        ++before;
        CHECK(p.last_frame == int(std::floor(s.flight_start * s.motion.fps + 1e-7)));
      }
      if (p.last_frame == last) {
        ++after;
        CHECK(p.first_frame == int(std::ceil(s.flight_end * s.motion.fps - 1e-7)));
        // Landed `distance` ahead.
        for (const FootPlant& q : s.plants)
          if (q.point == FootPoint::Toe && q.side == p.side && q.first_frame == 0)
            CHECK(p.world.z() - q.world.z() == Approx(o.distance).margin(1e-12));
      }
    }
    CHECK(before == 2);
    CHECK(after == 2);
    // Starts and ends standing still.
    const Eigen::Vector3d r0 = k.joint(0, s.figure.hips), r1 = k.joint(1, s.figure.hips);
    const Eigen::Vector3d rn = k.joint(last, s.figure.hips), rm = k.joint(last - 1, s.figure.hips);
    CHECK((r1 - r0).norm() < 1e-9);
    CHECK((rn - rm).norm() < 1e-9);
    CHECK(rn.y() == Approx(r0.y()).margin(1e-9));
  }
}

TEST_CASE("jump: a countermovement before takeoff, an absorbing crouch after landing", "[synth][jump]") {
  const Synthesis& s = default_jump();
  const Kinematics k(s.motion);
  const double fps = s.motion.fps;
  const int off = int(std::floor(s.flight_start * fps)), land = int(std::ceil(s.flight_end * fps));
  const double stand = k.joint(0, s.figure.hips).y();
  double low_before = 1e9, low_after = 1e9;
  for (int f = 0; f < off; ++f) low_before = std::min(low_before, k.joint(f, s.figure.hips).y());
  for (int f = land; f < k.frames(); ++f) low_after = std::min(low_after, k.joint(f, s.figure.hips).y());
  INFO("crouch " << stand - low_before << " m, landing crouch " << stand - low_after << " m, flight "
                 << s.flight_end - s.flight_start << " s, takeoff " << s.takeoff_velocity_up << " up, "
                 << s.takeoff_velocity_forward << " forward m/s");
  CHECK(stand - low_before > 0.1);
  CHECK(stand - low_before < 0.4);
  CHECK(stand - low_after > 0.1);
  CHECK(s.takeoff_velocity_forward > 0);
  // Heels rise before the toes leave.
  for (const FootPlant& p : s.plants)
    if (p.point == FootPoint::Heel && p.first_frame == 0) CHECK(p.last_frame < off - 5);
}

TEST_CASE("jump: every channel is continuous and C1", "[synth][jump]") {
  const Synthesis& s = default_jump();
  const ChannelSmoothness r = smoothness(s.motion, false);
  INFO("largest step " << r.max_step << " in " << s.motion.skeleton->channel_name(r.max_step_channel));
  CHECK(r.max_step < 0.2);  // at 120 fps; the arms swing fastest
  const Synthesis lo = synthesize_jump({.fps = 240});
  const Synthesis hi = synthesize_jump({.fps = 960});
  const ChannelSmoothness a = smoothness(lo.motion, false), b = smoothness(hi.motion, false);
  INFO("max |second difference| / dt^2: "
       << a.max_accel << " at 240 fps (" << lo.motion.skeleton->channel_name(a.max_accel_channel) << "), "
       << b.max_accel << " at 960 fps (" << hi.motion.skeleton->channel_name(b.max_accel_channel) << ")");
  CHECK(b.max_accel < 1.5 * a.max_accel);  // a kink would give about 4
}

TEST_CASE("jump: frame rates sample the same motion", "[synth][jump]") {
  const Synthesis a = synthesize_jump({.fps = 30});
  const Synthesis b = synthesize_jump({.fps = 120});
  CHECK(a.motion.duration() == Approx(b.motion.duration()).margin(1 / 30.0));
  CHECK(a.flight_start == b.flight_start);
  CHECK(a.flight_end == b.flight_end);
  for (int f = 0; f < a.motion.frame_count() && 4 * f < b.motion.frame_count(); ++f)
    for (int ch = 0; ch < a.motion.values.cols(); ++ch)
      REQUIRE(a.motion.values(f, ch) == Approx(b.motion.values(4 * f, ch)).margin(1e-9));
}

TEST_CASE("jump: every height and distance in range either jumps cleanly or is refused as too flat",
          "[synth][jump]") {
  int made = 0;
  for (double height : {0.05, 0.15, 0.3, 0.45, 0.6}) {
    for (double distance : {0.0, 0.5, 1.0, 1.5, 2.0}) {
      CAPTURE(height, distance);
      const double vy = std::sqrt(2 * 9.81 * height);
      try {
        const Synthesis s = synthesize_jump({.height = height, .distance = distance, .fps = 60});
        ++made;
        const Kinematics k(s.motion);
        const PlantErrors e = plant_errors(s, k);
        CHECK(e.drift < 1e-6);
        CHECK(lowest_sole(s, k) > -1e-9);
        CHECK(s.max_leg_extension < 0.999);
        CHECK(s.takeoff_velocity_forward <= 2 * vy);
      } catch (const std::invalid_argument& e) {
        // Only a long, low jump (flatter than about 27 degrees) is refused, and it says why.
        CHECK(distance >= 1.5);
        CHECK(height <= 0.1);
        CHECK_THAT(e.what(), Catch::Contains("raise the height or shorten the distance"));
      }
    }
  }
  CHECK(made >= 22);
}

TEST_CASE("jump: bad options are refused with the option named", "[synth][jump]") {
  CHECK_THROWS_WITH(synthesize_jump({.height = 0}),
                    Catch::Contains("height 0 m") && Catch::Contains("expected"));
  CHECK_THROWS_WITH(synthesize_jump({.height = 2}), Catch::Contains("height 2 m"));
  CHECK_THROWS_WITH(synthesize_jump({.distance = -1}), Catch::Contains("distance -1 m"));
  CHECK_THROWS_WITH(synthesize_jump({.gravity = 0}), Catch::Contains("gravity 0"));
  CHECK_THROWS_WITH(synthesize_jump({.fps = std::nan("")}), Catch::Contains("fps nan"));
  CHECK_THROWS_AS(synthesize_jump({.stature = 9}), std::invalid_argument);
}
