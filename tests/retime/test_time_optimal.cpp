#include <catch2/catch.hpp>

#include <cmath>

#include "kg/retime/time_optimal.hpp"

using namespace kg::retime;

namespace {

Polygon box(double a_lo, double a_hi, double b_lo, double b_hi) {
  return {{a_lo, b_lo}, {a_hi, b_lo}, {a_hi, b_hi}, {a_lo, b_hi}};
}

}  // namespace

TEST_CASE("time-optimal playback under an acceleration bound and a slow middle is bang-bang") {
  // 3 s of source at 30 fps; |p̈| <= 1 everywhere, ṗ² <= 4 except <= 1 for source seconds 1 to 2.
  const double fps = 30;
  std::vector<Polygon> hulls;
  for (int i = 0; i <= 90; ++i) hulls.push_back(box(-1, 1, 0, i >= 30 && i <= 60 ? 1 : 4));
  const TimeOptimalResult r = time_optimal(hulls, fps, {});
  REQUIRE(r.feasible);
  // Decelerating from ṗ² = 3 to 1 over the first second, 1 through the middle, accelerating back
  // to 3: 2 (√3 - 1) + 1 s.
  CHECK(r.duration == Approx(2 * (std::sqrt(3.0) - 1) + 1).epsilon(0.01));
  CHECK(r.pdot_squared.front() == Approx(3).epsilon(0.02));
  CHECK(r.pdot_squared[45] == Approx(1).epsilon(1e-9));
  for (std::size_t i = 0; i + 1 < r.pdot_squared.size(); ++i) {
    const double a = (r.pdot_squared[i + 1] - r.pdot_squared[i]) * fps / 2;
    CHECK(std::abs(a) <= 1 + 1e-9);
  }
  // The fitted spline plays the profile.
  CHECK(r.warp.duration == Approx(r.duration));
  CHECK(r.warp.at(r.output_times[45]) == Approx(1.5).margin(0.01));
}

TEST_CASE("time-optimal playback reports the frame no timing can pass") {
  std::vector<Polygon> hulls(10, box(-1, 1, 2, 3));
  for (int i = 5; i < 10; ++i) hulls[static_cast<std::size_t>(i)] = box(-1, 1, 0, 0.5);
  const TimeOptimalResult r = time_optimal(hulls, 30, {});
  CHECK_FALSE(r.feasible);
  CHECK(r.blocking_frame == 4);
  CHECK_THAT(r.message, Catch::Matchers::Contains("source frame 4"));
}

TEST_CASE("a point hull admits a box around it, so a ballistic stretch passes at its own speed") {
  std::vector<Polygon> hulls(30, box(-5, 5, 0, 9));
  for (int i = 10; i < 20; ++i) hulls[static_cast<std::size_t>(i)] = {{0.0, 1.0}};
  const TimeOptimalResult r = time_optimal(hulls, 30, {});
  REQUIRE(r.feasible);
  for (int i = 10; i < 20; ++i)
    CHECK(r.pdot_squared[static_cast<std::size_t>(i)] == Approx(1).epsilon(0.051));
}

TEST_CASE("a time-optimal playback that nearly stops still gives an increasing warp within the clip") {
  // Frames 28-32 admit only ṗ² <= 0.01: the frames there lie far apart in output time, and a
  // spline with knots closer than that swung backwards before the knots followed the gaps.
  std::vector<Polygon> hulls;
  for (int i = 0; i <= 60; ++i) hulls.push_back(box(-20, 20, 0, i >= 28 && i <= 32 ? 0.01 : 16));
  const TimeOptimalResult r = time_optimal(hulls, 30, {});
  REQUIRE(r.feasible);
  CHECK(r.warp.strictly_increasing());
  for (double t = 0; t <= r.duration; t += 0.01) {
    CHECK(r.warp.at(t) >= -1e-9);
    CHECK(r.warp.at(t) <= 2 + 1e-9);
  }
}

TEST_CASE("a playback slowed to a near stop is refused before its spline would need millions of knots") {
  std::vector<Polygon> hulls;
  for (int i = 0; i <= 60; ++i) hulls.push_back(box(-20, 20, 0, i >= 28 && i <= 32 ? 1e-14 : 16));
  const TimeOptimalResult r = time_optimal(hulls, 30, {});
  CHECK_FALSE(r.feasible);
  CHECK(r.warp.controls.empty());
  CHECK_THAT(r.message, Catch::Matchers::Contains("more than 4096 knots") &&
                            Catch::Matchers::Contains("playback nearly stops somewhere"));
}

TEST_CASE("fit_warp refuses samples that do not start at the origin or do not increase") {
  CHECK_THROWS_WITH(fit_warp({0, 0.5, 1}, {0.5, 1, 1.5}, 4), Catch::Matchers::Contains("start at output 0"));
  CHECK_THROWS_WITH(fit_warp({0, 0.5, 0.4}, {0, 1, 1.5}, 4), Catch::Matchers::Contains("does not follow"));
}
