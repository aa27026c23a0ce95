// The shared filters (kg/motion/filters.hpp): angle unwrapping and Gaussian smoothing with either
// end model, on curves built here.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include "kg/motion/filters.hpp"

using namespace kg::motion;

namespace {
constexpr double kPi = std::numbers::pi;
}

TEST_CASE("unwrap_angles removes 2 pi jumps and leaves the rest bit for bit", "[filters]") {
  std::vector<double> angles;
  for (int f = 0; f < 200; ++f) angles.push_back(std::remainder(0.2 * f - 1.0, 2 * kPi));
  const std::vector<double> original = angles;
  const std::vector<int> turns = unwrap_angles(angles);
  REQUIRE(turns.size() == angles.size());
  CHECK(turns[0] == 0);
  for (std::size_t f = 1; f < angles.size(); ++f) CHECK(angles[f] - angles[f - 1] == Approx(0.2));
  for (std::size_t f = 0; f < angles.size(); ++f) {
    if (turns[f] == 0) CHECK(angles[f] == original[f]);  // untouched exactly
    CHECK(angles[f] == Approx(original[f] + 2 * kPi * turns[f]));
  }
  CHECK(turns.back() == 6);  // 0.2 * 199 = 39.8 rad of travel: six whole turns added
  CHECK(unwrap_turns(original) == turns);

  SECTION("backwards and by several turns at once") {
    std::vector<double> down = {0.5, 0.5 - 4 * kPi + 0.1, 0.5 - 4 * kPi + 0.2};
    CHECK(unwrap_angles(down) == std::vector<int>{0, 2, 2});
    CHECK(down[1] == Approx(0.6));
  }
  SECTION("a step of exactly pi is motion, not a wrap") {
    CHECK(unwrap_turns(std::vector<double>{0.0, kPi}) == std::vector<int>{0, 0});
    CHECK(unwrap_turns(std::vector<double>{0.0, std::nextafter(kPi, 4.0)}) == std::vector<int>{0, -1});
  }
  SECTION("empty and one sample") {
    std::vector<double> none;
    CHECK(unwrap_angles(none).empty());
    std::vector<double> one = {7.0};
    CHECK(unwrap_angles(one) == std::vector<int>{0});
    CHECK(one[0] == 7.0);
  }
}

TEST_CASE("odd_extended continues a line as itself at any distance", "[filters]") {
  const std::vector<double> line = {1.0, 1.5, 2.0, 2.5};
  for (long i = -20; i <= 20; ++i) CHECK(odd_extended(line, i) == Approx(1.0 + 0.5 * static_cast<double>(i)));
  const std::vector<double> one = {3.0};
  CHECK(odd_extended(one, -5) == 3.0);
}

TEST_CASE("gaussian_smoothed: response, ends and refusals", "[filters]") {
  const int n = 120;
  SECTION("a constant stays constant, a line stays a line (odd reflection)") {
    Eigen::MatrixXd curves(n, 2);
    for (int f = 0; f < n; ++f) {
      curves(f, 0) = 4.25;
      curves(f, 1) = 0.1 * f - 3;
    }
    const Eigen::MatrixXd out = gaussian_smoothed(curves, 3.0, CurveEnds::OddReflection);
    for (int f = 0; f < n; ++f) {
      CHECK(out(f, 0) == Approx(4.25).margin(1e-12));
      CHECK(out(f, 1) == Approx(0.1 * f - 3).margin(1e-12));
    }
  }
  SECTION("a parabola keeps its curvature to the last sample (parabola ends)") {
    Eigen::MatrixXd flight(n, 1);
    for (int f = 0; f < n; ++f) flight(f, 0) = -0.5 * 0.01 * f * f + 0.3 * f;
    const Eigen::MatrixXd parabola = gaussian_smoothed(flight, 2.0, CurveEnds::Parabola);
    const Eigen::MatrixXd reflected = gaussian_smoothed(flight, 2.0, CurveEnds::OddReflection);
    // Smoothing a parabola c t^2 + ... adds the constant c times the kernel's variance (about
    // sigma^2) in the interior; at the ends too with parabola ends, while the reflection
    // straightens the curve there.
    const double shift = parabola(60, 0) - flight(60, 0);
    CHECK(shift == Approx(-0.005 * 4.0).epsilon(1e-3));
    for (int f : {0, 1, n - 2, n - 1}) CHECK(parabola(f, 0) - flight(f, 0) == Approx(shift).margin(1e-9));
    CHECK(reflected(60, 0) - flight(60, 0) == Approx(shift).margin(1e-12));
    CHECK(std::abs(reflected(n - 1, 0) - flight(n - 1, 0) - shift) > 1e-3);
  }
  SECTION("it removes high frequencies and keeps low ones") {
    Eigen::MatrixXd curves(n, 2);
    for (int f = 0; f < n; ++f) {
      curves(f, 0) = std::sin(2 * kPi * f / 60.0);  // slow
      curves(f, 1) = std::sin(2 * kPi * f / 3.0);   // a third of the sampling rate
    }
    const Eigen::MatrixXd out = gaussian_smoothed(curves, 2.0, CurveEnds::OddReflection);
    // The continuous kernel's response exp(-2 pi^2 sigma^2 f^2): 0.978 at f = 1/60, 1.5e-4 at 1/3.
    CHECK(out.col(0).segment(20, 80).cwiseAbs().maxCoeff() == Approx(0.978).margin(0.01));
    CHECK(out.col(1).segment(20, 80).cwiseAbs().maxCoeff() < 3e-4);
  }
  SECTION("a curve shorter than the kernel, and one sample") {
    Eigen::MatrixXd two(2, 1);
    two << 1.0, 2.0;
    const Eigen::MatrixXd p = gaussian_smoothed(two, 10.0, CurveEnds::Parabola);
    CHECK(p(0, 0) == Approx(1.0));
    CHECK(p(1, 0) == Approx(2.0));
    Eigen::MatrixXd one(1, 3);
    one << 1, 2, 3;
    CHECK(gaussian_smoothed(one, 2.0, CurveEnds::OddReflection) == one);
  }
  SECTION("sigma must be positive, finite and not absurd") {
    const Eigen::MatrixXd c = Eigen::MatrixXd::Zero(10, 1);
    for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL, 1e7})
      CHECK_THROWS_AS(gaussian_smoothed(c, bad, CurveEnds::Parabola), std::invalid_argument);
  }
}
