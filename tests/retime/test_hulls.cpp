// Hulls of bodies whose feasible timings are known in closed form (a point mass, a point mass on a
// force-limited leg, a box sliding or tipping), the centre LP, flight and infeasible frames.
#include <catch2/catch.hpp>

#include <cmath>
#include <sstream>

#include "hull_test_bodies.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"

using namespace kg;
using namespace kg::retime;
using namespace kg::body;
using kg::test::touching;

namespace {

constexpr double kG = 9.81;

std::string describe(const FrameHull& h) {
  std::ostringstream out;
  out << to_string(h.status) << ", " << h.lp_count << " LPs, message '" << h.message << "', vertices:";
  for (const Eigen::Vector2d& v : h.vertices) out << " (" << v.x() << ", " << v.y() << ")";
  return out.str();
}

// Every expected vertex is a hull vertex (within tol) and the hull has no other.
void check_vertices(const FrameHull& h, const std::vector<Eigen::Vector2d>& expected, double tol) {
  INFO(describe(h));
  REQUIRE(h.vertices.size() == expected.size());
  for (const Eigen::Vector2d& e : expected) {
    double nearest = INFINITY;
    for (const Eigen::Vector2d& v : h.vertices) nearest = std::min(nearest, (v - e).norm());
    INFO("expected (" << e.x() << ", " << e.y() << ")");
    CHECK(nearest < tol);
  }
}

void check_counter_clockwise(const FrameHull& h) {
  const std::size_t n = h.vertices.size();
  for (std::size_t i = 0; i < n && n >= 3; ++i) {
    const Eigen::Vector2d a = h.vertices[i], b = h.vertices[(i + 1) % n], c = h.vertices[(i + 2) % n];
    const Eigen::Vector2d e1 = b - a, e2 = c - b;
    CHECK(e1.x() * e2.y() - e1.y() * e2.x() > 0);
  }
}

// λ at each vertex and the centre meets every row.
void check_vertex_lambdas(const BodyModel& body, const FrameTorques& t, const FrameHull& h, double tol) {
  for (std::size_t i = 0; i < h.vertices.size(); ++i) {
    INFO("vertex " << i << " (" << h.vertices[i].x() << ", " << h.vertices[i].y() << ")");
    CHECK(max_row_violation(body, t, h, h.vertices[i], h.lambda[i]) < tol);
  }
  CHECK(max_row_violation(body, t, h, h.centre, h.centre_lambda) < tol);
}

}  // namespace

TEST_CASE("A point mass on the floor: the hull is the friction cone's triangle", "[hulls]") {
  // f = m (q'' ṗ² + q' p̈ − g) must lie in the pyramid |f_x| + |f_z| <= μ f_y. With q' = (1, 0, 0),
  // q'' = (0, −2, 0), μ = 0.5: |p̈| <= 0.5 (9.81 − 2 ṗ²), a triangle.
  const auto pm = kg::test::point_mass(2.0);
  const FrameTorques t = pm.torques({1, 0, 0}, {0, -2, 0});
  const Eigen::RowVectorXd pose = Eigen::RowVectorXd::Zero(3);
  const double h0 = 0.5 * kG;
  const std::vector<Eigen::Vector2d> triangle{{-h0, 0}, {h0, 0}, {0, kG / 2}};

  SECTION("one vertex") {
    const FrameHull h = build_frame_hull(pm.body, touching(pm.skeleton, pose, {{0, {0, 0, 0}}}), t, {});
    CHECK(h.status == HullStatus::Feasible);
    check_vertices(h, triangle, 1e-6);
    check_counter_clockwise(h);
    check_vertex_lambdas(pm.body, t, h, 1e-6);
    CHECK(h.column_count() == 4);
    CHECK(h.centre_is_original);
    CHECK(h.centre == Eigen::Vector2d(0, 1));
    CHECK(h.message.empty());
    for (std::uint8_t b : h.on_box) CHECK(b == 0);
    CHECK(h.lp_count <= 8 + 3 + 1);  // the sweep, one check per edge, the centre
  }
  SECTION("four vertices (a square sole): the same cone, sixteen λ") {
    const FrameHull h = build_frame_hull(
        pm.body,
        touching(pm.skeleton, pose,
                 {{0, {0.1, 0, 0.1}}, {0, {-0.1, 0, 0.1}}, {0, {-0.1, 0, -0.1}}, {0, {0.1, 0, -0.1}}}),
        t, {});
    check_vertices(h, triangle, 1e-6);
    check_vertex_lambdas(pm.body, t, h, 1e-6);
    CHECK(h.column_count() == 16);
  }
}

TEST_CASE("Hull vertices on the box say so", "[hulls]") {
  // Accelerating upwards (q'' = (0, 2, 0)) widens the cone with speed: |p̈| <= 0.5 (9.81 + 2 ṗ²)
  // until the box |p̈| <= 20, ṗ² <= 16 cuts it.
  const auto pm = kg::test::point_mass(2.0);
  const FrameTorques t = pm.torques({1, 0, 0}, {0, 2, 0});
  const FrameHull h =
      build_frame_hull(pm.body, touching(pm.skeleton, Eigen::RowVectorXd::Zero(3), {{0, {0, 0, 0}}}), t, {});
  const double s1 = (40 - kG) / 2;
  check_vertices(h, {{-kG / 2, 0}, {kG / 2, 0}, {20, s1}, {20, 16}, {-20, 16}, {-20, s1}}, 1e-6);
  for (std::size_t i = 0; i < h.vertices.size(); ++i) {
    std::uint8_t want = 0;
    if (h.vertices[i].x() > 19.99) want |= kBoxPddotMax;
    if (h.vertices[i].x() < -19.99) want |= kBoxPddotMin;
    if (h.vertices[i].y() > 15.99) want |= kBoxPdot2Max;
    CHECK(h.on_box[i] == want);
  }
  SECTION("an LP budget too small for the tolerance is reported") {
    const FrameHull few =
        build_frame_hull(pm.body, touching(pm.skeleton, Eigen::RowVectorXd::Zero(3), {{0, {0, 0, 0}}}), t,
                         {.initial_directions = 3, .max_lps = 4});
    INFO(describe(few));
    CHECK(few.message.find("LP limit (4) reached") != std::string::npos);
    CHECK(few.lp_count == 5);  // the budget, then the centre
    check_vertex_lambdas(pm.body, t, few, 1e-6);
  }
  SECTION("another box") {
    const FrameHull small =
        build_frame_hull(pm.body, touching(pm.skeleton, Eigen::RowVectorXd::Zero(3), {{0, {0, 0, 0}}}), t,
                         {.pddot_max = 8, .pdot2_max = 4});
    check_vertices(
        small, {{-kG / 2, 0}, {kG / 2, 0}, {8, (16 - kG) / 2}, {8, 4}, {-8, 4}, {-8, (16 - kG) / 2}}, 1e-6);
  }
}

TEST_CASE("Torque limits cut the hull: a point mass on a force-limited leg", "[hulls]") {
  // The leg's row is −f_y within ±60 N: f_y = 2 (2 ṗ² + 9.81) <= 60 gives ṗ² <= 10.095; friction
  // gives |p̈| <= ṗ² + 4.905.
  const auto l = kg::test::leg(2.0, 60.0);
  const FrameTorques t = l.torques({1, 0, 0}, {0, 2, 0});
  const FrameHull h = build_frame_hull(l.body, touching(l.skeleton, l.pose(), {{1, {0, 0, 0}}}), t, {});
  const double top = (30 - kG) / 2;
  check_vertices(h, {{-kG / 2, 0}, {kG / 2, 0}, {top + kG / 2, top}, {-top - kG / 2, top}}, 1e-6);
  check_vertex_lambdas(l.body, t, h, 1e-6);
  CHECK(h.centre_is_original);
  for (std::uint8_t b : h.on_box) CHECK(b == 0);

  SECTION("a limit too low for the body's weight: infeasible, the least-squares point") {
    // f_y >= 2 * 9.81 whatever the timing, the leg allows 10 N: the least squares trades the root's
    // vertical row against the leg's excess, at ṗ² = 0: residual (m g − F) / √2.
    const auto weak = kg::test::leg(2.0, 10.0);
    const FrameTorques tw = weak.torques({0, 0, 0}, {0, 2, 0});
    const FrameHull hw =
        build_frame_hull(weak.body, touching(weak.skeleton, weak.pose(), {{1, {0, 0, 0}}}), tw, {});
    INFO(describe(hw));
    CHECK(hw.status == HullStatus::Infeasible);
    REQUIRE(hw.vertices.size() == 1);
    CHECK(hw.vertices[0].x() == Approx(0).margin(1e-6));
    CHECK(hw.vertices[0].y() == Approx(0).margin(1e-6));
    CHECK(hw.residual == Approx((2 * kG - 10) / std::sqrt(2.0)).epsilon(1e-6));
    CHECK(hw.message.find("infeasible") != std::string::npos);
    // The contact force is the compromise (m g + F) / 2, straight up.
    int hint = 0;
    Eigen::VectorXd lambda;
    lambda_at(hw, {0.3, 2.0}, hint, lambda);  // constant everywhere for a one-point hull
    const std::vector<PatchForce> f = patch_forces(hw, lambda);
    REQUIRE(f.size() == 1);
    CHECK(f[0].force.y() == Approx((2 * kG + 10) / 2).epsilon(1e-6));
    CHECK(f[0].force.x() == Approx(0).margin(1e-6));
    CHECK(f[0].force.z() == Approx(0).margin(1e-6));
  }
}

TEST_CASE("A fixed base without contact: the torque limits alone make the hull", "[hulls]") {
  // An arm turning about Z under a fixed root (no channels), τ = 2 ṗ² + p̈ + (0, 1, 0)·g within
  // ±10 N m: the strip −0.19 <= p̈ + 2 ṗ² <= 19.81 cut by the box.
  using motion::ChannelKind;
  auto sk = kg::test::skeleton_of(
      {{.name = "base", .parent = -1}, {.name = "arm", .parent = 0, .channels = {{ChannelKind::Zrotation}}}});
  BodyModel body = kg::test::body_of(sk, 0.5);
  body.segments[1].mass = 1;
  body.torque_min[0] = -10;
  body.torque_max[0] = 10;
  FrameTorques t;
  t.velocity = Eigen::VectorXd::Constant(1, 2.0);
  t.acceleration = Eigen::VectorXd::Constant(1, 1.0);
  t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(1, 3);
  t.gravity(0, 1) = 1;
  const FrameHull h = build_frame_hull(body, ContactFrame{}, t, {});
  CHECK(h.status == HullStatus::Feasible);
  CHECK(h.column_count() == 0);
  check_vertices(h, {{-0.19, 0}, {19.81, 0}, {19.81 - 32, 16}, {-20, 16}, {-20, 19.81 / 2}}, 1e-6);
  check_vertex_lambdas(body, t, h, 1e-6);
  CHECK(h.centre_is_original);
}

TEST_CASE("A box on two corners: tipping, not friction, limits how fast it may slide", "[hulls]") {
  // A box of width w = 0.25 and height h = 1 (centre of mass at its middle) sliding along X with its
  // bottom corners on the floor: moments about the centre of mass need |F_x| <= (w / h) F_y, which
  // is tighter than friction (μ = 0.5). With c' = (1, 0, 0), c'' = (0, 3, 0):
  // |p̈| <= 0.25 (3 ṗ² + 9.81), up to the box's ṗ² <= 16.
  const auto box = kg::test::planar_box(10.0, 0.9);
  const double w = 0.25, hh = 1.0;
  const FrameTorques t = box.torques({1, 0, 0, 0}, {0, 3, 0, 0});
  const Eigen::RowVectorXd pose = (Eigen::RowVectorXd(4) << 0, hh / 2, 0, 0).finished();
  const ContactFrame corners = touching(box.skeleton, pose,
                                        {{0, {-w / 2, -hh / 2, 0.2}},
                                         {0, {w / 2, -hh / 2, 0.2}},
                                         {0, {w / 2, -hh / 2, -0.2}},
                                         {0, {-w / 2, -hh / 2, -0.2}}});
  const FrameHull h = build_frame_hull(box.body, corners, t, {});
  const double top = 0.25 * (3 * 16 + kG);  // at the box's ṗ² = 16
  check_vertices(h, {{-0.25 * kG, 0}, {0.25 * kG, 0}, {top, 16}, {-top, 16}}, 1e-6);
  check_vertex_lambdas(box.body, t, h, 1e-6);
}

TEST_CASE("A box tipping about an edge has one timing per speed: a segment", "[hulls]") {
  // Pivot at the origin, centre of mass at R(θ) ρ from it. Rotation about the pivot: I_p θ̈ =
  // m (R ρ × g)_z with I_p = I + m |ρ|², θ̈ = θ'' ṗ² + θ' p̈: a line in the plane. The source is
  // physical at (0, 1) by choosing θ''.
  const double m = 10, inertia = 0.4, mu = 0.8;
  const auto box = kg::test::planar_box(m, inertia, mu);
  const Eigen::Vector2d rho(0.3, 0.5);  // pivot -> centre of mass, body frame
  const double theta = 0.2, omega = 1.5;
  const Eigen::Vector2d r = Eigen::Rotation2Dd(theta) * rho;  // world
  const double ip = inertia + m * rho.squaredNorm();
  const double torque = m * (r.x() * -kG - r.y() * 0.0);  // (R ρ × g)_z with g = (0, −9.81)
  const double alpha = torque / ip;
  // c = pivot + R ρ: c' = ω ẑ × Rρ, c'' = α ẑ × Rρ − ω² Rρ.
  const Eigen::Vector2d perp(-r.y(), r.x());
  const Eigen::Vector2d cd = omega * perp, cdd = alpha * perp - omega * omega * r;
  const FrameTorques t = box.torques({cd.x(), cd.y(), 0, omega}, {cdd.x(), cdd.y(), 0, alpha});
  const Eigen::RowVectorXd pose = (Eigen::RowVectorXd(4) << r.x(), r.y(), 0, theta).finished();
  const ContactFrame pivot = touching(box.skeleton, pose, {{0, {-rho.x(), -rho.y(), 0}}});
  CHECK(pivot.points[0].world.norm() < 1e-12);
  const FrameHull h = build_frame_hull(box.body, pivot, t, {});
  INFO(describe(h));
  REQUIRE(h.status == HullStatus::Feasible);
  REQUIRE(h.vertices.size() == 2);
  CHECK(h.message.find("segment") != std::string::npos);
  // Both ends on the line I_p (α ṗ² + ω p̈) = torque.
  for (const Eigen::Vector2d& v : h.vertices)
    CHECK(ip * (alpha * v.y() + omega * v.x()) == Approx(torque).epsilon(1e-7));
  // The ends: where the line meets the cone (f = m (c'' s + c' a − g) in |f_x| <= μ f_y, f_y >= 0)
  // or the box, found here along the line by its parameter s.
  auto a_of = [&](double s) { return (torque / ip - alpha * s) / omega; };
  auto feasible = [&](double s) {
    const double a = a_of(s);
    const Eigen::Vector2d f = m * (cdd * s + cd * a - Eigen::Vector2d(0, -kG));
    return s >= 0 && s <= 16 && std::abs(a) <= 20 && f.y() >= 0 && std::abs(f.x()) <= mu * f.y();
  };
  REQUIRE(feasible(1.0));
  auto edge = [&](double inside, double outside) {
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (inside + outside);
      (feasible(mid) ? inside : outside) = mid;
    }
    return inside;
  };
  const double s_low = feasible(0) ? 0.0 : edge(1.0, 0.0), s_high = feasible(16) ? 16.0 : edge(1.0, 16.0);
  std::vector<Eigen::Vector2d> ends{{a_of(s_low), s_low}, {a_of(s_high), s_high}};
  check_vertices(h, ends, 1e-6);
  check_vertex_lambdas(box.body, t, h, 1e-6);
  CHECK(h.centre_is_original);
  // The force model of a segment: λ along it interpolates, λ off it extends along the normal.
  int hint = 0;
  Eigen::VectorXd lambda;
  const Eigen::Vector2d mid = 0.5 * (h.vertices[0] + h.vertices[1]);
  lambda_at(h, mid, hint, lambda);
  CHECK(max_row_violation(box.body, t, h, mid, lambda) < 1e-6);
  const Eigen::Vector2d e = (h.vertices[1] - h.vertices[0]).normalized();
  Eigen::VectorXd off;
  lambda_at(h, mid + 0.3 * Eigen::Vector2d(e.y(), -e.x()), hint, off);
  CHECK((off - lambda).norm() < 1e-9 * (1 + lambda.norm()));
  const HullPoint c = closest_point(h, mid + 0.3 * Eigen::Vector2d(e.y(), -e.x()), hint);
  CHECK((c.point - mid).norm() < 1e-9);
  CHECK(c.distance_squared == Approx(0.09));
}

TEST_CASE("Flight frames: the least-squares point of the root's rows", "[hulls]") {
  const auto pm = kg::test::point_mass(3.0);
  const ContactFrame none;
  SECTION("a parabola under the same gravity is exactly (0, 1)") {
    const FrameHull h = build_frame_hull(pm.body, none, pm.torques({1, 2, 0.5}, {0, -kG, 0}), {});
    INFO(describe(h));
    CHECK(h.status == HullStatus::Flight);
    REQUIRE(h.vertices.size() == 1);
    CHECK(h.vertices[0] == Eigen::Vector2d(0, 1));
    CHECK(h.centre == Eigen::Vector2d(0, 1));
    CHECK(h.centre_is_original);
    CHECK(h.residual < 1e-12);
    CHECK(h.column_count() == 0);
    CHECK(h.message.find("flight") != std::string::npos);
  }
  SECTION("at the apex (q' = 0) p̈ is free: the point nearest (0, 1)") {
    const FrameHull h = build_frame_hull(pm.body, none, pm.torques({0, 0, 0}, {0, -kG, 0}), {});
    CHECK(h.vertices[0].x() == Approx(0).margin(1e-12));
    CHECK(h.vertices[0].y() == Approx(1).epsilon(1e-12));
  }
  SECTION("a path no timing makes ballistic: the least-squares compromise") {
    // Rows m (ṗ², −9.81 ṗ² + 9.81, 0): ṗ² = g² / (1 + g²).
    const FrameHull h = build_frame_hull(pm.body, none, pm.torques({0, 0, 0}, {1, -kG, 0}), {});
    CHECK(h.vertices[0].y() == Approx(kG * kG / (1 + kG * kG)).epsilon(1e-7));
    CHECK(h.residual == Approx(3 * kG / std::sqrt(1 + kG * kG)).epsilon(1e-6));
    CHECK_FALSE(h.centre_is_original);
  }
  SECTION("the box bounds it too") {
    // Rows m (−4.905 ṗ² + 9.81): ṗ² = 2 exactly, but the box stops at 1.5.
    const FrameHull h =
        build_frame_hull(pm.body, none, pm.torques({0, 0, 0}, {0, -kG / 2, 0}), {.pdot2_max = 1.5});
    CHECK(h.vertices[0].y() == Approx(1.5));
    CHECK(h.on_box[0] == kBoxPdot2Max);
  }
}

TEST_CASE("The centre: minimal summed patch forces at (0, 1), or the nearest hull point", "[hulls]") {
  const auto pm = kg::test::point_mass(2.0);
  const Eigen::RowVectorXd pose = Eigen::RowVectorXd::Zero(3);
  SECTION("two feet do not push against each other") {
    // q' = (1, 0, 0), q'' = (1, 0, 0): at (0, 1) the feet must give F = (2, 19.62, 0) together; the
    // summed L1 norms are at least |F_x| + F_y, reached only without opposing horizontal forces.
    const FrameTorques t = pm.torques({1, 0, 0}, {1, 0, 0});
    const FrameHull h =
        build_frame_hull(pm.body, touching(pm.skeleton, pose, {{0, {0.2, 0, 0}}, {0, {-0.2, 0, 0}}}), t, {});
    REQUIRE(h.centre_is_original);
    const std::vector<PatchForce> f = patch_forces(h, h.centre_lambda);
    REQUIRE(f.size() == 2);
    double l1 = 0;
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (const PatchForce& p : f) {
      l1 += p.force.cwiseAbs().sum();
      total += p.force;
    }
    CHECK((total - Eigen::Vector3d(2, 2 * kG, 0)).norm() < 1e-6);
    CHECK(l1 == Approx(2 + 2 * kG).epsilon(1e-9));
  }
  SECTION("(0, 1) outside the hull") {
    // q'' = (0, −12, 0): f_y = 2 (9.81 − 12 ṗ²) >= 0 needs ṗ² <= 0.8175.
    const FrameTorques t = pm.torques({1, 0, 0}, {0, -12, 0});
    const FrameHull h = build_frame_hull(pm.body, touching(pm.skeleton, pose, {{0, {0, 0, 0}}}), t, {});
    INFO(describe(h));
    CHECK_FALSE(h.centre_is_original);
    CHECK(h.centre.x() == Approx(0).margin(1e-9));
    CHECK(h.centre.y() == Approx(kG / 12).epsilon(1e-9));
    CHECK(h.message.find("outside the hull") != std::string::npos);
    check_vertex_lambdas(pm.body, t, h, 1e-6);
  }
}

TEST_CASE("build_hulls runs a clip frame by frame and counts the statuses", "[hulls]") {
  const auto pm = kg::test::point_mass(2.0);
  // Three frames: standing, flying ballistically, standing.
  motion::Motion m{pm.skeleton, motion::FrameMatrix::Zero(3, 3), 30.0, "hop"};
  m.values(1, 1) = 0.5;
  const std::vector<ContactPatch> patches{{"foot", {{0, {0, 0, 0}}}}};
  const Contacts c = assemble_contacts(m, patches, {{true}, {false}, {true}});
  const std::vector<FrameTorques> t{pm.torques({1, 0, 0}, {0, -2, 0}), pm.torques({1, 1, 0}, {0, -kG, 0}),
                                    pm.torques({1, 0, 0}, {0, -2, 0})};
  const Hulls h = build_hulls(pm.body, c, t, {});
  REQUIRE(h.frames.size() == 3);
  CHECK(h.count(HullStatus::Feasible) == 2);
  CHECK(h.count(HullStatus::Flight) == 1);
  CHECK(h.frames[1].vertices[0] == Eigen::Vector2d(0, 1));
  CHECK(h.patch_names == std::vector<std::string>{"foot"});
  CHECK(h.gravity == pm.body.gravity);

  SECTION("bad input") {
    CHECK_THROWS_WITH(build_hulls(pm.body, c, std::span(t).first(2), {}),
                      Catch::Contains("3 contact frames but 2 frames"));
    CHECK_THROWS_WITH(build_hulls(pm.body, c, t, {.tolerance = 0}), Catch::Contains("tolerance"));
    CHECK_THROWS_WITH(build_hulls(pm.body, c, t, {.pddot_max = -1}),
                      Catch::Contains("HullOptions.pddot_max = -1.0"));
    CHECK_THROWS_WITH(build_hulls(pm.body, c, t, {.initial_directions = 2}),
                      Catch::Contains("initial_directions"));
    BodyModel short_limits = pm.body;
    short_limits.torque_max.resize(2);
    CHECK_THROWS_WITH(build_hulls(short_limits, c, t, {}), Catch::Contains("torque limits"));
    std::vector<FrameTorques> wrong = t;
    wrong[2].velocity.resize(5);
    CHECK_THROWS_WITH(build_hulls(pm.body, c, wrong, {}), Catch::Contains("channels"));
  }
}
