#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "synth_test_util.hpp"

using namespace kg;
using namespace kg::synth;
using namespace kg::synth::test;

namespace {

const Synthesis& default_walk() {
  static const Synthesis s = synthesize_walk({});
  return s;
}

// Steps counted from the motion alone: a foot that was clearly off the floor (lowest sole point
// above 8 mm: the synthesizer keeps 1.5 cm of clearance in mid-swing for a 1.75 m figure, scaled
// with stature) and comes back onto it (below 1 mm) has taken a step.
int counted_steps(const Synthesis& s, const Kinematics& k) {
  int steps = 0;
  for (Side side : {kLeft, kRight}) {
    bool airborne = false;
    for (int f = 0; f < k.frames(); ++f) {
      const double low = sole(k, s.figure, f, side).lowest();
      if (low > 0.008) airborne = true;
      if (airborne && low < 1e-3) {
        ++steps;
        airborne = false;
      }
    }
  }
  return steps;
}

}  // namespace

TEST_CASE("walk: planted heel, ankle, ball and toe stay put on the floor", "[synth][walk]") {
  const Synthesis& s = default_walk();
  const Kinematics k(s.motion);
  const PlantErrors e = plant_errors(s, k);
  INFO("max drift " << e.drift << " m, max height error " << e.height << " m over " << e.frames_checked
                    << " frames");
  CHECK(e.frames_checked > s.motion.frame_count());  // both feet, several points each
  CHECK(e.drift < 1e-6);                             // exact up to rounding (the brief allows 1 mm)
  CHECK(e.height < 1e-6);
  // Every foot landing gives a heel plant (plus each foot's standing start).
  int heels = 0;
  for (const FootPlant& p : s.plants) heels += p.point == FootPoint::Heel;
  CHECK(heels == s.steps + 2);
}

TEST_CASE("walk: stance phases roll heel strike, foot flat, heel off, toe off", "[synth][walk]") {
  const Synthesis& s = default_walk();
  const Kinematics k(s.motion);
  // For each landing: the heel is planted before the ball/toe (heel strike then foot flat), and
  // the heel lifts before the toe (heel off then toe off).
  for (Side side : {kLeft, kRight}) {
    std::vector<const FootPlant*> heel, toe;
    for (const FootPlant& p : s.plants) {
      if (p.side != side) continue;
      if (p.point == FootPoint::Heel) heel.push_back(&p);
      if (p.point == FootPoint::Toe) toe.push_back(&p);
    }
    REQUIRE(heel.size() == toe.size());
    for (std::size_t i = 1; i < heel.size(); ++i) {  // the first is the standing start
      CAPTURE(side, i);
      CHECK(heel[i]->first_frame < toe[i]->first_frame);
      if (i + 1 < heel.size()) {
        CHECK(heel[i]->last_frame < toe[i]->last_frame);
        // Between heel off and toe off the heel is up and rising.
        const int mid = (heel[i]->last_frame + toe[i]->last_frame) / 2;
        CHECK(sole(k, s.figure, mid, side).heel.y() > 0.01);
      }
      // At heel strike the toes are up.
      CHECK(sole(k, s.figure, heel[i]->first_frame, side).toe_tip.y() > 0.02);
    }
  }
}

TEST_CASE("walk: no foot goes through the floor", "[synth][walk]") {
  const Synthesis& s = default_walk();
  const Kinematics k(s.motion);
  const double low = lowest_sole(s, k);
  INFO("lowest sole point " << low << " m");
  CHECK(low > -1e-9);  // the brief allows 1 mm
}

TEST_CASE("walk: the requested number of steps at the requested speed", "[synth][walk]") {
  for (int steps : {2, 3, 8}) {
    for (double speed : {0.6, 1.3, 1.9}) {
      CAPTURE(steps, speed);
      const Synthesis s = synthesize_walk({.steps = steps, .speed = speed, .fps = 60});
      const Kinematics k(s.motion);
      CHECK(s.steps == steps);
      CHECK(counted_steps(s, k) == steps);
      if (steps < 3) continue;
      // Root speed between the first and last full step.
      const double fps = s.motion.fps;
      const int f0 = int(std::ceil(s.steady_start * fps)), f1 = int(std::floor(s.steady_end * fps));
      REQUIRE(f1 > f0);
      const Eigen::Vector3d a = k.joint(f0, s.figure.hips), b = k.joint(f1, s.figure.hips);
      const double forward = (b.z() - a.z()) / ((f1 - f0) / fps);
      double path = 0;  // the horizontal path, sway included
      for (int f = f0 + 1; f <= f1; ++f) {
        Eigen::Vector3d d = k.joint(f, s.figure.hips) - k.joint(f - 1, s.figure.hips);
        d.y() = 0;
        path += d.norm();
      }
      INFO("forward speed " << forward << ", horizontal path speed " << path / ((f1 - f0) / fps));
      CHECK(forward == Approx(speed).epsilon(0.01));
      CHECK(path / ((f1 - f0) / fps) == Approx(speed).epsilon(0.05));
      // Whole clip: starts and ends at rest, travels (steps - 1) step lengths.
      const Eigen::Vector3d first = k.joint(0, s.figure.hips), last = k.joint(k.frames() - 1, s.figure.hips);
      CHECK(last.z() - first.z() == Approx((steps - 1) * s.gait.step_length).epsilon(1e-9));
      CHECK((k.joint(1, s.figure.hips) - first).norm() < 1e-9);
    }
  }
}

TEST_CASE("walk: gait relation gives plausible step length and cadence", "[synth][walk]") {
  const GaitParameters g = gait_from_speed(1.3, 1.75);
  INFO("step " << g.step_length << " m, cadence " << 60 / g.step_time << " steps/min");
  CHECK(g.step_length == Approx(1.3 * g.step_time));
  CHECK(g.step_length > 0.6);
  CHECK(g.step_length < 0.8);
  CHECK(60 / g.step_time > 100);
  CHECK(60 / g.step_time < 120);
  CHECK(g.double_support_time() > 0);
  // Faster: longer steps and higher cadence; taller: longer steps at the same speed.
  CHECK(gait_from_speed(1.8, 1.75).step_length > g.step_length);
  CHECK(gait_from_speed(1.8, 1.75).step_time < g.step_time);
  CHECK(gait_from_speed(1.3, 2.0).step_length > g.step_length);
  // Footprints: consecutive landings one step length apart along +Z.
  const Synthesis& s = default_walk();
  std::vector<double> strikes;  // z of each landing's heel plant, in time order
  std::vector<std::pair<int, double>> timed;
  for (const FootPlant& p : s.plants)
    if (p.point == FootPoint::Heel && p.first_frame > 0) timed.push_back({p.first_frame, p.world.z()});
  std::sort(timed.begin(), timed.end());
  REQUIRE(timed.size() == std::size_t(s.steps));
  for (std::size_t i = 1; i + 1 < timed.size(); ++i)
    CHECK(timed[i].second - timed[i - 1].second == Approx(s.gait.step_length).epsilon(1e-9));
  CHECK(timed.back().second == Approx(timed[timed.size() - 2].second).margin(1e-12));  // feet together
}

TEST_CASE("walk: pelvis bobs and sways, arms swing against the legs", "[synth][walk]") {
  const Synthesis& s = default_walk();
  const Kinematics k(s.motion);
  const Figure& fig = s.figure;
  const double fps = s.motion.fps;
  const int f0 = int(std::ceil(s.steady_start * fps)), f1 = int(std::floor(s.steady_end * fps));
  double ymin = 1e9, ymax = -1e9, xmin = 1e9, xmax = -1e9, corr = 0, hand2 = 0, foot2 = 0;
  double max_knee = 0, min_knee = 1e9;
  for (int f = f0; f <= f1; ++f) {
    const Eigen::Vector3d root = k.joint(f, fig.hips);
    ymin = std::min(ymin, root.y());
    ymax = std::max(ymax, root.y());
    xmin = std::min(xmin, root.x());
    xmax = std::max(xmax, root.x());
    const double hand = k.joint(f, fig.hand[kLeft]).z() - root.z();
    const double foot = k.joint(f, fig.foot[kLeft]).z() - root.z();
    corr += hand * foot;
    hand2 += hand * hand;
    foot2 += foot * foot;
    const double knee = s.motion.values(f, fig.skeleton->joint(fig.leg[kLeft]).first_channel + 1);
    max_knee = std::max(max_knee, knee);
    min_knee = std::min(min_knee, knee);
  }
  corr /= std::sqrt(hand2 * foot2);
  INFO("bob " << ymax - ymin << " m, sway " << xmax - xmin << " m, hand-foot correlation " << corr
              << ", knee " << min_knee * 180 / std::numbers::pi << ".." << max_knee * 180 / std::numbers::pi
              << " deg");
  CHECK(ymax - ymin > 0.015);
  CHECK(ymax - ymin < 0.08);
  CHECK(xmax - xmin > 0.01);
  CHECK(xmax - xmin < 0.08);
  CHECK(corr < -0.5);
  // Knee flexion: nearly straight in stance, around 60 degrees in swing (Perry: 0-5 to 60-70).
  CHECK(min_knee > 0);
  CHECK(min_knee < 0.3);
  CHECK(max_knee > 0.8);
  CHECK(max_knee < 1.4);
  CHECK(s.max_leg_extension < 0.999);
}

TEST_CASE("walk: every channel is continuous and C1", "[synth][walk]") {
  const Synthesis& s = default_walk();
  const ChannelSmoothness r = smoothness(s.motion, false);
  INFO("largest step " << r.max_step << " in " << s.motion.skeleton->channel_name(r.max_step_channel));
  CHECK(r.max_step < 0.1);  // radians per frame at 120 fps: 12 rad/s (early-swing knee and ankle reach 8)
  // C1: the second difference over dt^2 stays bounded as the frame rate rises (a kink would make
  // it grow like 1 / dt).
  const Synthesis lo = synthesize_walk({.fps = 240});
  const Synthesis hi = synthesize_walk({.fps = 960});
  const ChannelSmoothness a = smoothness(lo.motion, false), b = smoothness(hi.motion, false);
  INFO("max |second difference| / dt^2: "
       << a.max_accel << " at 240 fps (" << lo.motion.skeleton->channel_name(a.max_accel_channel) << "), "
       << b.max_accel << " at 960 fps (" << hi.motion.skeleton->channel_name(b.max_accel_channel) << ")");
  CHECK(b.max_accel < 1.5 * a.max_accel);  // a kink would give about 4
}

TEST_CASE("walk: frame rates sample the same motion", "[synth][walk]") {
  const Synthesis a = synthesize_walk({.steps = 4, .fps = 30});
  const Synthesis b = synthesize_walk({.steps = 4, .fps = 120});
  const Synthesis c = synthesize_walk({.steps = 4, .fps = 97});
  CHECK(a.motion.duration() == Approx(b.motion.duration()).margin(1 / 30.0));
  CHECK(c.motion.duration() == Approx(b.motion.duration()).margin(1 / 97.0));
  // Frame f at 30 fps is frame 4 f at 120 fps.
  for (int f = 0; f < a.motion.frame_count() && 4 * f < b.motion.frame_count(); ++f)
    for (int ch = 0; ch < a.motion.values.cols(); ++ch)
      REQUIRE(a.motion.values(f, ch) == Approx(b.motion.values(4 * f, ch)).margin(1e-9));
}

TEST_CASE("walk: other statures, speeds and step counts keep the feet planted", "[synth][walk]") {
  for (double stature : {1.2, 1.6, 2.2}) {
    for (double speed : {0.4, 2.0}) {
      CAPTURE(stature, speed);
      const Synthesis s = synthesize_walk({.steps = 5, .speed = speed, .stature = stature, .fps = 50});
      const Kinematics k(s.motion);
      const PlantErrors e = plant_errors(s, k);
      CHECK(e.drift < 1e-6);
      CHECK(e.height < 1e-6);
      CHECK(lowest_sole(s, k) > -1e-9);
      CHECK(counted_steps(s, k) == 5);
      CHECK(s.max_leg_extension < 0.999);
      CHECK(s.motion.skeleton->rest_height() == Approx(stature));
    }
  }
}

TEST_CASE("walk: bad options are refused with the option named", "[synth][walk]") {
  CHECK_THROWS_WITH(synthesize_walk({.steps = 1}),
                    Catch::Contains("steps 1") && Catch::Contains("expected 2 to 200"));
  CHECK_THROWS_WITH(synthesize_walk({.speed = 0}), Catch::Contains("speed 0 m/s"));
  CHECK_THROWS_WITH(synthesize_walk({.speed = 3.5}), Catch::Contains("speed 3.5"));
  CHECK_THROWS_WITH(synthesize_walk({.speed = std::nan("")}), Catch::Contains("speed nan"));
  CHECK_THROWS_WITH(synthesize_walk({.stature = 0.3}), Catch::Contains("stature 0.3 m"));
  CHECK_THROWS_WITH(synthesize_walk({.fps = 0}), Catch::Contains("fps 0"));
  CHECK_THROWS_AS(synthesize_walk({.fps = -120}), std::invalid_argument);
  CHECK_THROWS_AS(gait_from_speed(-1, 1.75), std::invalid_argument);
}
