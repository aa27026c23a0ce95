#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "kg/motion/rotations.hpp"
#include "kg/retime/path.hpp"

using namespace kg;

namespace {

// A root with one position and one rotation channel following known curves at 60 fps.
motion::Motion known_curves(int frames, double fps) {
  auto skeleton = std::make_shared<motion::Skeleton>();
  skeleton->add_joint(
      {.name = "root",
       .channels = {{.kind = motion::ChannelKind::Xposition}, {.kind = motion::ChannelKind::Yrotation}}});
  motion::Motion m{skeleton, motion::FrameMatrix::Zero(frames, 2), fps, "curves"};
  for (int f = 0; f < frames; ++f) {
    const double t = f / fps;
    m.values(f, 0) = 0.5 * t * t * t;              // x = t³/2
    m.values(f, 1) = motion::wrap_angle(3.0 * t);  // turns through +-180 degrees
  }
  return m;
}

}  // namespace

TEST_CASE("path_derivatives match the curves' own derivatives, through angle wrapping") {
  const double fps = 60;
  const motion::Motion m = known_curves(200, fps);
  const retime::PathDerivatives d = retime::path_derivatives(m);
  for (int f = 0; f < m.frame_count(); ++f) {
    const double t = f / fps;
    CHECK(d.first(f, 0) == Approx(1.5 * t * t).margin(2e-3));
    CHECK(d.second(f, 0) == Approx(3.0 * t).margin(2e-3));
    CHECK(d.first(f, 1) == Approx(3.0).margin(1e-9));
    CHECK(d.second(f, 1) == Approx(0.0).margin(1e-6));
  }
}

TEST_CASE("path_derivatives of clips of one and two frames") {
  const retime::PathDerivatives one = retime::path_derivatives(known_curves(1, 30));
  CHECK(one.first.isZero());
  const motion::Motion two = known_curves(2, 30);
  const retime::PathDerivatives d = retime::path_derivatives(two);
  CHECK(d.first(1, 0) == Approx((two.values(1, 0) - two.values(0, 0)) * 30));
  CHECK(d.second.isZero());
}

TEST_CASE("smoothed path derivatives keep a parabola's second derivative and quieten noise") {
  const double fps = 120;
  motion::Motion m = known_curves(240, fps);
  for (int f = 0; f < m.frame_count(); ++f) {
    const double t = f / fps;
    m.values(f, 0) = 2 + 1.5 * t - 4.905 * t * t;  // a flight under 9.81 m/s²
  }
  motion::Motion noisy = m;
  std::uint32_t state = 7;
  for (int f = 0; f < m.frame_count(); ++f) {
    state = state * 1664525u + 1013904223u;
    noisy.values(f, 0) += 0.001 * ((state >> 8) / double(1 << 24) - 0.5);  // a millimetre of capture noise
  }
  const retime::PathDerivatives clean = retime::path_derivatives(m, 0.04);
  const retime::PathDerivatives raw = retime::path_derivatives(noisy);
  const retime::PathDerivatives smooth = retime::path_derivatives(noisy, 0.04);
  double raw_error = 0, smooth_error = 0;
  for (int f = 25; f + 25 < m.frame_count(); ++f) {  // beyond the kernel's reach of the ends
    CHECK(clean.second(f, 0) == Approx(-9.81).epsilon(1e-9));
    CHECK(clean.first(f, 0) == Approx(1.5 - 9.81 * f / fps).margin(1e-9));
    raw_error = std::max(raw_error, std::abs(raw.second(f, 0) + 9.81));
    smooth_error = std::max(smooth_error, std::abs(smooth.second(f, 0) + 9.81));
  }
  CHECK(raw_error > 20);
  CHECK(smooth_error < 1);
  CHECK_THROWS_WITH(retime::path_derivatives(m, -1), Catch::Matchers::Contains("smoothing"));
}

TEST_CASE(
    "smoothed path derivatives of a parabola are exact to its ends, also on clips shorter than the kernel") {
  // 0.04 s at 120 Hz: a kernel reaching 20 frames either side, longer than the short clips.
  const double fps = 120;
  for (const int frames : {3, 4, 7, 25, 240}) {
    motion::Motion m = known_curves(frames, fps);
    for (int f = 0; f < frames; ++f) {
      const double t = f / fps;
      m.values(f, 0) = 2 + 1.5 * t - 4.905 * t * t;  // a flight under 9.81 m/s²
      m.values(f, 1) = 0.3 - 2.0 * t;                // a steady turn
    }
    const retime::PathDerivatives d = retime::path_derivatives(m, 0.04);
    INFO(frames << " frames");
    for (int f = 0; f < frames; ++f) {
      INFO("frame " << f);
      CHECK(d.second(f, 0) == Approx(-9.81).epsilon(1e-9));
      CHECK(d.first(f, 0) == Approx(1.5 - 9.81 * f / fps).margin(1e-9));
      CHECK(d.first(f, 1) == Approx(-2.0).margin(1e-9));
      CHECK(d.second(f, 1) == Approx(0.0).margin(1e-6));
    }
  }
}

TEST_CASE("smoothed path derivatives of a clip of two frames: their difference, no curvature") {
  const motion::Motion two = known_curves(2, 120);
  const retime::PathDerivatives d = retime::path_derivatives(two, 0.04);
  for (int f = 0; f < 2; ++f) {
    CHECK(d.first(f, 0) == Approx((two.values(1, 0) - two.values(0, 0)) * 120));
    CHECK(d.first(f, 1) == Approx(3.0).margin(1e-9));
  }
  CHECK(d.second.isZero());
}
