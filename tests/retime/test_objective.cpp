#include <catch2/catch.hpp>

#include <random>

#include "kg/retime/objective.hpp"

using namespace kg::retime;

namespace {

// Frames of a 2 s clip at 30 fps: a box hull |p̈| <= 60, 0.1 <= ṗ² <= 30 whose torque term prefers
// the original timing, and a flight second (source 0.5 to 1.5 s) whose polytope is empty: the
// single point (0, 1).
BakedObjective box_and_flight(double alpha) {
  BakedObjective objective(30, alpha);
  for (int f = 0; f <= 60; ++f) {
    BakedFrame frame;
    const bool flight = f >= 15 && f <= 45;
    // τ = (ṗ² − 1, 0.5 p̈) against τ' = 0: a torque term (ṗ² − 1)² + 0.25 p̈².
    const Quadratic q = bake_quadratic(Eigen::Vector2d(-1, 0), Eigen::Vector2d(0, 0.5), Eigen::Vector2d(1, 0),
                                       Eigen::Vector2d::Zero(), 0.01);
    if (flight) {
      frame.vertices = {{0.0, 1.0}};
      frame.sectors = {q};
    } else {
      frame.vertices = {{-60, 0.1}, {60, 0.1}, {60, 30}, {-60, 30}};
      frame.centre = {0, 1};
      frame.sectors = {q, q, q, q};
    }
    objective.add_frame(frame);
  }
  objective.finish();
  return objective;
}

}  // namespace

TEST_CASE("bake_quadratic reproduces |τ − τ'|²") {
  const Eigen::Vector3d t0(1, 2, 3), ta(0.5, -1, 2), tb(-2, 0.3, 1), target(0.1, 0.2, -0.3);
  const Quadratic q = bake_quadratic(t0, ta, tb, target, 2.0);
  for (double a : {-1.0, 0.3}) {
    for (double b : {0.5, 2.0}) {
      const double direct = 2.0 * (t0 + ta * a + tb * b - target).squaredNorm();
      CHECK(q[0] * b * b + q[1] * a * a + q[2] * a * b + q[3] * b + q[4] * a + q[5] == Approx(direct));
    }
  }
}

TEST_CASE("closest_point on polygons, segments and points") {
  const std::vector<Eigen::Vector2d> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  CHECK(closest_point(square, {0.5, 0.5}).isApprox(Eigen::Vector2d(0.5, 0.5)));
  CHECK(closest_point(square, {2, 0.5}).isApprox(Eigen::Vector2d(1, 0.5)));
  CHECK(closest_point(square, {-1, -1}).isApprox(Eigen::Vector2d(0, 0)));
  CHECK(closest_point({{0, 0}, {2, 0}}, {1, 3}).isApprox(Eigen::Vector2d(1, 0)));
  CHECK(closest_point({{0.5, 1}}, {1, 3}).isApprox(Eigen::Vector2d(0.5, 1)));
}

TEST_CASE("the baked objective's partial derivatives match finite differences, inside and outside hulls") {
  const BakedObjective objective = box_and_flight(10);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> p(0.02, 1.98), a(-4, 4), b(-0.5, 7);
  for (int i = 0; i < 200; ++i) {
    const double pp = p(rng), aa = a(rng), bb = b(rng), h = 1e-6;
    int hint = 0;
    const SampleCost c = objective.evaluate(pp, aa, bb, hint);
    auto value = [&](double x, double y, double z) {
      int k = 0;
      return objective.evaluate(x, y, z, k).value;
    };
    CHECK(c.d_pddot == Approx((value(pp, aa + h, bb) - value(pp, aa - h, bb)) / (2 * h)).epsilon(1e-5).margin(1e-6));
    CHECK(c.d_pdot2 == Approx((value(pp, aa, bb + h) - value(pp, aa, bb - h)) / (2 * h)).epsilon(1e-5).margin(1e-6));
    // Within a frame interval the value is linear in p; across a frame time d_p jumps, so only
    // points off the frame times are checked.
    const double x = pp * 30 - std::floor(pp * 30);
    if (x > 1e-3 && x < 1 - 1e-3)
      CHECK(c.d_p == Approx((value(pp + h, aa, bb) - value(pp - h, aa, bb)) / (2 * h)).epsilon(1e-5).margin(1e-6));
  }
}

TEST_CASE("retiming a clip with a flight to a shorter duration keeps the flight at source speed") {
  // 2 s of source into 1.3 s: the flight second keeps its second, the other second of source
  // plays in 0.3 s.
  const BakedObjective objective = box_and_flight(1000);
  const RetimeResult r = retime(objective, {.duration = 1.3, .knot_spacing = 0.05});
  INFO(r.message);
  CHECK(r.converged);
  int ground = 0, inside = 0, flight = 0, flight_at_speed = 0;
  for (double t = 0; t <= 1.3; t += 0.005) {
    const WarpSample s = r.warp.sample(t);
    const int f = static_cast<int>(std::lround(s.p * 30));
    if (f >= 18 && f <= 42) ++flight, flight_at_speed += std::abs(s.pdot - 1) < 0.1;
    if (f < 15 || f > 45) ++ground, inside += objective.parts(f, s.pddot, s.pdot * s.pdot, 1e-6).inside;
  }
  CHECK(flight_at_speed == flight);
  CHECK(inside == ground);
}
