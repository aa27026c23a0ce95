// The fan force model: λ interpolated inside the hull meets every row, sectors cover the plane
// (with the centre inside, on an edge, at a vertex, or a one-point hull), the per-sector affine τ,
// patch forces, and the closest hull point with hints.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "hull_test_bodies.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"

using namespace kg;
using namespace kg::retime;
using namespace kg::body;
using kg::test::touching;

namespace {

constexpr double kG = 9.81;

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

struct Case {
  std::string name;
  BodyModel body;
  FrameTorques torques;
  FrameHull hull;
};

// Hulls with the centre inside, at a vertex, on an edge, and a sliding box with rotation.
std::vector<Case> cases() {
  std::vector<Case> out;
  const auto pm = kg::test::point_mass(2.0);
  const Eigen::RowVectorXd origin = Eigen::RowVectorXd::Zero(3);
  const ContactFrame square =
      touching(pm.skeleton, origin,
               {{0, {0.1, 0, 0.1}}, {0, {-0.1, 0, 0.1}}, {0, {-0.1, 0, -0.1}}, {0, {0.1, 0, -0.1}}});
  {
    const FrameTorques t = pm.torques({1, 0.2, 0.5}, {0.5, 2, 0});
    out.push_back(
        {"point mass, four vertices, centre inside", pm.body, t, build_frame_hull(pm.body, square, t, {})});
  }
  {
    const FrameTorques t = pm.torques({1, 0, 0}, {0, -12, 0});  // apex at (0, 0.8175) is the centre
    out.push_back({"point mass, centre at a vertex", pm.body, t, build_frame_hull(pm.body, square, t, {})});
  }
  {
    const auto l = kg::test::leg(2.0, 2 * (kG + 1.2));  // ṗ² <= 0.6: (0, 1) above the top edge
    const FrameTorques t = l.torques({1, 0, 0}, {0, 2, 0});
    out.push_back({"leg, centre on an edge", l.body, t,
                   build_frame_hull(
                       l.body, touching(l.skeleton, l.pose(), {{1, {0, 0, 0}}, {1, {0.1, 0, 0}}}), t, {})});
  }
  {
    const auto box = kg::test::planar_box(10.0, 0.9);
    const Eigen::RowVectorXd pose = (Eigen::RowVectorXd(4) << 0, 0.5, 0, 0.05).finished();
    const FrameTorques t = box.torques({1, 0.1, 0.3, 0.2}, {0.3, 3, 0, -0.4});
    const ContactFrame corners = touching(
        box.skeleton, pose,
        {{0, {-0.2, -0.5, 0.2}}, {0, {0.2, -0.5, 0.2}}, {0, {0.2, -0.5, -0.2}}, {0, {-0.2, -0.5, -0.2}}});
    out.push_back({"box on four corners", box.body, t, build_frame_hull(box.body, corners, t, {})});
  }
  return out;
}

// A random point of the hull: a random convex combination of its vertices.
Eigen::Vector2d inside(const FrameHull& h, std::mt19937& rng) {
  std::exponential_distribution<double> e(1.0);
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  double sum = 0;
  for (const Eigen::Vector2d& v : h.vertices) {
    const double w = e(rng);
    x += w * v;
    sum += w;
  }
  return x / sum;
}

Eigen::Vector2d anywhere(std::mt19937& rng) {
  std::uniform_real_distribution<double> a(-30, 30), s(-5, 25);
  return {a(rng), s(rng)};
}

}  // namespace

TEST_CASE("λ interpolated inside the hull meets every row", "[force_model]") {
  std::mt19937 rng(7);
  for (const Case& c : cases()) {
    INFO(c.name << ": " << c.hull.message);
    REQUIRE(c.hull.status == HullStatus::Feasible);
    REQUIRE(c.hull.vertices.size() >= 3);
    int hint = 0;
    Eigen::VectorXd lambda;
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector2d x = inside(c.hull, rng);
      lambda_at(c.hull, x, hint, lambda);
      INFO("at (" << x.x() << ", " << x.y() << ")");
      CHECK(max_row_violation(c.body, c.torques, c.hull, x, lambda) < 1e-6);
    }
    // The vertices and the centre give back their own λ.
    for (std::size_t i = 0; i < c.hull.vertices.size(); ++i) {
      lambda_at(c.hull, c.hull.vertices[i], hint, lambda);
      CHECK((lambda - c.hull.lambda[i]).norm() < 1e-9 * (1 + lambda.norm()));
    }
    lambda_at(c.hull, c.hull.centre, hint, lambda);
    CHECK((lambda - c.hull.centre_lambda).norm() < 1e-9 * (1 + lambda.norm()));
  }
}

TEST_CASE("The sectors cover the plane and λ is continuous across them", "[force_model]") {
  std::mt19937 rng(11);
  for (const Case& c : cases()) {
    INFO(c.name << ": " << c.hull.message);
    const FrameHull& h = c.hull;
    // Each sector spans a positive angle of at most half a turn; together they make one turn.
    double turn = 0;
    for (const FanSector& s : h.sectors) {
      const double angle = std::atan2(cross(s.from, s.to), s.from.dot(s.to));
      CHECK(angle > 0);
      turn += angle < 0 ? angle + 2 * std::numbers::pi : angle;
    }
    CHECK(turn == Approx(2 * std::numbers::pi));
    // Consecutive sectors share their ray.
    for (std::size_t k = 0; k < h.sectors.size(); ++k)
      CHECK((h.sectors[k].to - h.sectors[(k + 1) % h.sectors.size()].from).norm() < 1e-12);
    const bool on_boundary = !h.centre_is_original;
    CHECK(std::any_of(h.sectors.begin(), h.sectors.end(), [](const FanSector& s) { return !s.in_hull; }) ==
          on_boundary);
    int hint = 0;
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector2d x = anywhere(rng);
      const int k = find_sector(h, x, hint);
      const FanSector& s = h.sectors[static_cast<std::size_t>(k)];
      const Eigen::Vector2d d = x - h.centre;
      CHECK(cross(s.from, d) >= -1e-12 * d.norm() * s.from.norm());
      CHECK(cross(d, s.to) >= -1e-12 * d.norm() * s.to.norm());
      // Any hint finds the same sector (away from the rays).
      CHECK(find_sector(h, x, static_cast<int>(rng() % h.sectors.size())) == k);
      hint = k;
    }
    // λ on each ray is the same from both sides: evaluate both sectors' affine maps there.
    for (std::size_t k = 0; k < h.sectors.size(); ++k) {
      const FanSector& a = h.sectors[k];
      const FanSector& b = h.sectors[(k + 1) % h.sectors.size()];
      for (double t : {0.5, 1.0, 3.0}) {
        const Eigen::Vector2d x = h.centre + t * a.to;
        const Eigen::VectorXd la = a.lambda0 + a.lambda_pddot * x.x() + a.lambda_pdot2 * x.y();
        const Eigen::VectorXd lb = b.lambda0 + b.lambda_pddot * x.x() + b.lambda_pdot2 * x.y();
        CHECK((la - lb).norm() < 1e-9 * (1 + la.norm()));
      }
    }
  }
}

TEST_CASE("Outside the hull λ extends linearly, at a boundary centre, constant along the normals",
          "[force_model]") {
  std::vector<Case> all = cases();
  const Case& vertex = all[1];
  INFO(vertex.hull.message);
  REQUIRE_FALSE(vertex.hull.centre_is_original);
  // The centre is the apex (0, 0.8175): straight above it lies the normal cone, λ = the centre's.
  CHECK(vertex.hull.centre.y() == Approx(kG / 12));
  int hint = 0;
  Eigen::VectorXd lambda;
  lambda_at(vertex.hull, {0.0, 3.0}, hint, lambda);
  CHECK((lambda - vertex.hull.centre_lambda).norm() < 1e-9 * vertex.hull.centre_lambda.norm());
  CHECK_FALSE(vertex.hull.sectors[static_cast<std::size_t>(hint)].in_hull);
  // Along a sector's ray beyond a vertex λ keeps its slope (linear extrapolation).
  const Case& inside_case = all[0];
  const FrameHull& h = inside_case.hull;
  Eigen::VectorXd l1, l2, l3;
  const Eigen::Vector2d v = h.vertices[0], c = h.centre;
  lambda_at(h, c + 0.5 * (v - c), hint, l1);
  lambda_at(h, v, hint, l2);
  lambda_at(h, c + 1.5 * (v - c), hint, l3);
  CHECK(((l3 - l2) - (l2 - l1)).norm() < 1e-9 * (1 + l2.norm()));
}

TEST_CASE("A one-point hull has one λ everywhere", "[force_model]") {
  FrameHull h;
  h.vertices = {{0.2, 0.9}};
  h.lambda = {Eigen::Vector2d(3, 4)};
  h.centre = {0.2, 0.9};
  h.centre_lambda = Eigen::Vector2d(3, 4);
  build_fan(h);
  REQUIRE(h.sectors.size() == 4);
  std::mt19937 rng(3);
  int hint = 0;
  Eigen::VectorXd lambda;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d x = anywhere(rng);
    lambda_at(h, x, hint, lambda);
    CHECK(lambda == Eigen::VectorXd(Eigen::Vector2d(3, 4)));
    const HullPoint p = closest_point(h, x, hint);
    CHECK(p.point == Eigen::Vector2d(0.2, 0.9));
    CHECK(p.distance_squared == Approx((x - Eigen::Vector2d(0.2, 0.9)).squaredNorm()));
  }
  SECTION("bad hulls") {
    FrameHull empty;
    CHECK_THROWS_WITH(build_fan(empty), Catch::Contains("no vertex"));
    FrameHull sizes = h;
    sizes.centre_lambda = Eigen::Vector3d(1, 2, 3);
    CHECK_THROWS_WITH(build_fan(sizes), Catch::Contains("sizes"));
    FrameHull outside;
    outside.vertices = {{0, 0}, {1, 0}, {0, 1}};
    outside.lambda.assign(3, Eigen::VectorXd::Zero(1));
    outside.centre = {2, 2};
    outside.centre_lambda = Eigen::VectorXd::Zero(1);
    CHECK_THROWS_WITH(build_fan(outside), Catch::Contains("outside the hull"));
  }
}

TEST_CASE("A segment hull with the centre at one end: finite λ everywhere", "[force_model]") {
  // The fan has one ray (to the far end), its two normals and the half-turn between them.
  FrameHull h;
  h.vertices = {{0.3, 1.3}, {1.4, 0.0}};
  h.lambda = {Eigen::Vector2d(1, 2), Eigen::Vector2d(5, 0)};
  h.centre = h.vertices[0];
  h.centre_lambda = Eigen::Vector2d(1, 3);
  build_fan(h);
  REQUIRE(h.sectors.size() == 3);
  std::mt19937 rng(17);
  int hint = 0;
  Eigen::VectorXd lambda;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d x = anywhere(rng);
    lambda_at(h, x, hint, lambda);
    REQUIRE(lambda.allFinite());
    // λ varies along the segment only: it is the centre's on the far side of the centre.
    const Eigen::Vector2d e = h.vertices[1] - h.vertices[0];
    if ((x - h.centre).dot(e) <= 0) CHECK((lambda - h.centre_lambda).norm() < 1e-9);
  }
  lambda_at(h, h.vertices[1], hint, lambda);
  CHECK((lambda - h.lambda[1]).norm() < 1e-9);
  lambda_at(h, 0.5 * (h.vertices[0] + h.vertices[1]), hint, lambda);
  CHECK((lambda - Eigen::Vector2d(3, 1.5)).norm() < 1e-9);
}

TEST_CASE("τ is affine per sector and equals the rows at λ(p̈, ṗ²)", "[force_model]") {
  std::mt19937 rng(5);
  for (const Case& c : cases()) {
    INFO(c.name);
    const FrameHull& h = c.hull;
    int hint = 0;
    Eigen::VectorXd lambda;
    SectorTorques st;
    for (int i = 0; i < 100; ++i) {
      const Eigen::Vector2d x = i % 2 ? inside(h, rng) : anywhere(rng);
      lambda_at(h, x, hint, lambda);
      sector_torques(h, hint, c.torques, c.body.gravity, st);
      const Eigen::VectorXd affine = st.t0 + st.pddot * x.x() + st.pdot2 * x.y();
      const Eigen::VectorXd direct = c.torques.at(x.y(), x.x(), c.body.gravity) - h.N * lambda;
      CHECK((affine - direct).norm() < 1e-9 * (1 + direct.norm()));
    }
  }
  const Case c = cases().front();
  SectorTorques st;
  CHECK_THROWS_WITH(sector_torques(c.hull, -1, c.torques, c.body.gravity, st),
                    Catch::Contains("out of range"));
}

TEST_CASE("Patch forces: Newton's law for the point mass, centres of pressure on the sole", "[force_model]") {
  const auto pm = kg::test::point_mass(2.0);
  const Eigen::Vector3d qd(1, 0.2, 0.5), qdd(0.5, 2, 0);
  const FrameTorques t = pm.torques(qd, qdd);
  // Two patches: a square sole and a point.
  motion::Motion m{pm.skeleton, motion::FrameMatrix::Zero(1, 3), 30.0, "pose"};
  const Contacts contacts = assemble_contacts(
      m,
      {{"sole", {{0, {0.1, 0, 0.1}}, {0, {-0.1, 0, 0.1}}, {0, {-0.1, 0, -0.1}}, {0, {0.1, 0, -0.1}}}},
       {"stick", {{0, {0.5, 0.3, 0}}}}},
      {{true, true, true, true, true}});
  const FrameHull h = build_frame_hull(pm.body, contacts.frames[0], t, {});
  std::mt19937 rng(9);
  int hint = 0;
  Eigen::VectorXd lambda;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d x = inside(h, rng);
    lambda_at(h, x, hint, lambda);
    const std::vector<PatchForce> f = patch_forces(h, lambda);
    REQUIRE(f.size() == 2);
    CHECK(f[0].patch == 0);
    CHECK(f[1].patch == 1);
    const Eigen::Vector3d newton = pm.mass * (qdd * x.y() + qd * x.x() - pm.body.gravity);
    CHECK((f[0].force + f[1].force - newton).norm() < 1e-6);
    if (f[0].force.y() > 1e-6) {
      CHECK(std::abs(f[0].centre_of_pressure.x()) <= 0.1 + 1e-9);
      CHECK(std::abs(f[0].centre_of_pressure.z()) <= 0.1 + 1e-9);
      CHECK(f[0].centre_of_pressure.y() == Approx(0).margin(1e-12));
    }
    CHECK((f[1].centre_of_pressure - Eigen::Vector3d(0.5, 0.3, 0)).norm() < 1e-12);
  }
  CHECK_THROWS_WITH(patch_forces(h, Eigen::VectorXd::Zero(3)), Catch::Contains("3 λ for 20 columns"));
}

TEST_CASE("The closest hull point, with and without hints", "[force_model]") {
  std::mt19937 rng(13);
  for (const Case& c : cases()) {
    INFO(c.name);
    const FrameHull& h = c.hull;
    int hint = 0;
    // A random walk (the retimer's successive queries) and random jumps.
    Eigen::Vector2d x = h.centre;
    std::normal_distribution<double> step(0, 0.7);
    for (int i = 0; i < 400; ++i) {
      x = i % 50 == 0 ? anywhere(rng) : Eigen::Vector2d(x + Eigen::Vector2d(step(rng), step(rng)));
      const HullPoint fast = closest_point(h, x, hint);
      const HullPoint slow = closest_point_on_polygon(h.vertices, x);
      INFO("query (" << x.x() << ", " << x.y() << ")");
      CHECK(fast.inside == slow.inside);
      CHECK(fast.distance_squared == Approx(slow.distance_squared).margin(1e-12));
      CHECK((fast.point - slow.point).norm() < 1e-9);
      if (fast.inside) CHECK(fast.point == x);
    }
  }
  // Thin hulls (points of a flat ellipse) with the centre on an edge or at a vertex, where a point
  // in a wedge outside at the centre may see the far side of the hull closer than the near one.
  for (int i = 0; i < 200; ++i) {
    std::uniform_real_distribution<double> unit(0, 1);
    FrameHull h;
    const int n = 3 + static_cast<int>(unit(rng) * 8);
    std::vector<double> angles;
    for (int k = 0; k < n; ++k) angles.push_back(2 * std::numbers::pi * unit(rng));
    std::sort(angles.begin(), angles.end());
    for (double a : angles) h.vertices.emplace_back(15 * std::cos(a), 1 + 0.3 * std::sin(a));
    const std::size_t j = static_cast<std::size_t>(unit(rng) * n);
    h.centre = i % 2 ? h.vertices[j]
                     : Eigen::Vector2d(0.5 * (h.vertices[j] + h.vertices[(j + 1) % h.vertices.size()]));
    h.lambda.assign(h.vertices.size(), Eigen::VectorXd());
    h.centre_lambda = Eigen::VectorXd();
    build_fan(h);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector2d x = anywhere(rng);
      int hint = k;
      const HullPoint fast = closest_point(h, x, hint);
      const HullPoint slow = closest_point_on_polygon(h.vertices, x);
      INFO("hull " << i << " query (" << x.x() << ", " << x.y() << ")");
      CHECK(fast.inside == slow.inside);
      CHECK(fast.distance_squared == Approx(slow.distance_squared).margin(1e-12));
      CHECK((fast.point - slow.point).norm() < 1e-9);
    }
  }
  // A segment and a point.
  const std::vector<Eigen::Vector2d> segment{{0, 0}, {2, 0}};
  HullPoint p = closest_point_on_polygon(segment, {1, 1});
  CHECK(p.point == Eigen::Vector2d(1, 0));
  CHECK(p.distance_squared == Approx(1));
  CHECK_FALSE(p.inside);
  p = closest_point_on_polygon(std::vector<Eigen::Vector2d>{{1, 1}}, {1, 1});
  CHECK(p.inside);
  CHECK(p.distance_squared == 0);
}
