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
  skeleton->add_joint({.name = "root",
                       .channels = {{.kind = motion::ChannelKind::Xposition}, {.kind = motion::ChannelKind::Yrotation}}});
  motion::Motion m{skeleton, motion::FrameMatrix::Zero(frames, 2), fps, "curves"};
  for (int f = 0; f < frames; ++f) {
    const double t = f / fps;
    m.values(f, 0) = 0.5 * t * t * t;                               // x = t³/2
    m.values(f, 1) = motion::wrap_angle(3.0 * t);                   // turns through +-180 degrees
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
