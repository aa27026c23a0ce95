#include <catch2/catch.hpp>

#include <random>

#include "kg/retime/force_model.hpp"
#include "kg/retime/objective.hpp"

using namespace kg::retime;

namespace {

// A 2 s clip at 30 fps of a body with two channels and no contact columns: τ = (ṗ² − 1, 0.5 p̈),
// so the torque term against τ' = 0 is (ṗ² − 1)² + 0.25 p̈² (times 0.01). Its hull is a box
// |p̈| <= 60, 0.1 <= ṗ² <= 30, except for a flight second (source 0.5 to 1.5 s) whose polytope is
// empty: the single point (0, 1).
struct BoxAndFlight {
  kg::motion::Skeleton skeleton;  // a root with the two channels
  Hulls hulls;
  std::vector<FrameTorques> torques;
  std::vector<Eigen::VectorXd> targets;
};

BoxAndFlight box_and_flight() {
  BoxAndFlight c;
  c.skeleton.add_joint({.name = "root",
                        .channels = {{.kind = kg::motion::ChannelKind::Xposition},
                                     {.kind = kg::motion::ChannelKind::Yposition}}});
  FrameTorques t;
  t.velocity = Eigen::Vector2d(1, 0);
  t.acceleration = Eigen::Vector2d(0, 0.5);
  t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(2, 3);
  t.gravity(0, 1) = 1 / 9.81;  // g = (0, -9.81, 0) gives -1
  for (int f = 0; f <= 60; ++f) {
    FrameHull hull;
    hull.N = Eigen::MatrixXd::Zero(2, 0);
    if (f >= 15 && f <= 45) {
      hull.status = HullStatus::Flight;
      hull.vertices = {{0.0, 1.0}};
    } else {
      hull.vertices = {{-60, 0.1}, {60, 0.1}, {60, 30}, {-60, 30}};
    }
    hull.lambda.assign(hull.vertices.size(), Eigen::VectorXd());
    hull.on_box.assign(hull.vertices.size(), 0);
    hull.centre_lambda = Eigen::VectorXd();
    build_fan(hull);
    c.hulls.frames.push_back(hull);
    c.torques.push_back(t);
    c.targets.push_back(Eigen::Vector2d::Zero());
  }
  return c;
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

TEST_CASE("the baked objective's partial derivatives match finite differences, inside and outside hulls") {
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 10, .beta = 0.01});
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

TEST_CASE("the baked torque term is the force model's |τ − τ'|² in every sector") {
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 1, .beta = 2, .torque_scale = 0.5});
  for (int f : {3, 20}) {
    for (const Eigen::Vector2d& x : {Eigen::Vector2d(0, 1), Eigen::Vector2d(5, 3), Eigen::Vector2d(-100, -2)}) {
      const Eigen::VectorXd tau = c.torques[static_cast<std::size_t>(f)].at(x.y(), x.x(), c.hulls.gravity);
      CHECK(objective.parts(f, x.x(), x.y()).torque == Approx(2 * tau.squaredNorm() / 0.25));
    }
  }
  CHECK(objective.parts(3, 0, 1).inside);
  // The flight's admissible timings do not depend on α: with α = 0 the region is still there.
  const BakedObjective no_alpha(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 0, .beta = 1});
  CHECK(no_alpha.admissible_region(20, 0.1).size() == 16);
  CHECK(no_alpha.flight_excess(20, 0, 1.5) == Approx(0.25));
  CHECK_FALSE(objective.parts(20, 0, 1.5).inside);
  CHECK(objective.parts(20, 0, 1.5).feasibility == Approx(0.25));
}

TEST_CASE("retiming a clip with a flight to a shorter duration keeps the flight at source speed") {
  // 2 s of source into 1.3 s: the flight second keeps its second, the other second of source
  // plays in 0.3 s.
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 1000, .beta = 0.01});
  const RetimeResult r = retime(objective, {.duration = 1.3, .knot_spacing = 0.05});
  INFO(r.message);
  CHECK(r.converged);
  int flight = 0, flight_at_speed = 0;
  double worst_outside = 0;  // plane units, on the ground
  for (double t = 0; t <= 1.3; t += 0.005) {
    const WarpSample s = r.warp.sample(t);
    const int f = static_cast<int>(std::lround(s.p * 30));
    if (f >= 18 && f <= 42) ++flight, flight_at_speed += std::abs(s.pdot - 1) < 0.1;
    if (f < 15 || f > 45)
      worst_outside = std::max(worst_outside, std::sqrt(objective.parts(f, s.pddot, s.pdot * s.pdot).feasibility / 1000));
  }
  CHECK(flight_at_speed == flight);
  CHECK(worst_outside < 0.5);  // against a box 120 wide and 30 high: the speed-up after landing
}
