// The ladder plugin (plugins/ladder): ladder.rung and ladder.rail loaded at run time from
// KG_PLUGIN_DIR as `kg.ConstraintKind` extensions (never linked into the test), evaluated on hand
// computed cases, their derivatives against central finite differences, their checks refused.
#include <cmath>
#include <memory>

#include <catch2/catch.hpp>

#include "kg/graph/plugin_loader.hpp"
#include "kg/retarget/nodes.hpp"  // kg.ConstraintKind
#include "plugin_test_util.hpp"

using namespace kg_test;
using Catch::Matchers::Contains;
using kg::retarget::Constraint;
using kg::retarget::ConstraintKind;

namespace {

fs::path ladder_library() {
  return fs::path(KG_PLUGIN_DIR) / "kg_ladder.so";
}

struct Ladder {
  Registry registry;
  PluginLoader loader{registry};
  Ladder() { loader.load_file(ladder_library()); }
  std::shared_ptr<const ConstraintKind> kind(const std::string& name) const {
    std::shared_ptr<const ConstraintKind> found = registry.find<ConstraintKind>(name);
    REQUIRE(found != nullptr);
    return found;
  }
};

Constraint segment(const std::string& kind, std::vector<double> params) {
  Constraint c;
  c.kind = kind;
  c.label = "test " + kind;
  c.points = {{.character = 0, .joint = 3, .local = {0, 0, 0.05}}};
  c.params = std::move(params);
  c.samples = {{.frames = {10}}};
  return c;
}

struct Eval {
  Eigen::VectorXd r;
  Eigen::MatrixXd dp;
};
Eval evaluate(const ConstraintKind& kind, const Constraint& c, const Eigen::Vector3d& p) {
  Eval e{Eigen::VectorXd::Zero(kind.rows(c)), Eigen::MatrixXd::Zero(kind.rows(c), 3)};
  Eigen::MatrixXd dv = Eigen::MatrixXd::Zero(kind.rows(c), 0);
  const Eigen::Vector3d points[1] = {p};
  kind.evaluate(c, c.params, points, {}, e.r, e.dp, dv);
  return e;
}

}  // namespace

TEST_CASE("the ladder plugin exports two constraint kinds", "[ladder]") {
  Ladder ladder;
  REQUIRE(ladder.loader.loaded().size() == 1);
  CHECK(ladder.loader.loaded().at(0).id == "kg.ladder");
  CHECK(ladder.registry.names<ConstraintKind>() == std::vector<std::string>{"ladder.rail", "ladder.rung"});
  CHECK(ladder.registry.node_type_names().empty());
  for (const char* name : {"ladder.rung", "ladder.rail"}) {
    auto kind = ladder.kind(name);
    CHECK(kind->name() == name);
    CHECK_THAT(kind->doc(), Contains("7.2"));
    const Constraint c = segment(name, {0, 1, 0, 1, 1, 0});
    CHECK_NOTHROW(kind->check(c));
    REQUIRE(kind->rows(c) == 4);
    CHECK_FALSE(kind->is_inequality(c, 0));
    CHECK_FALSE(kind->is_inequality(c, 1));
    CHECK(kind->is_inequality(c, 2));
    CHECK(kind->is_inequality(c, 3));
  }
}

TEST_CASE("ladder.rung: distance from the rung's line and the two ends, by hand", "[ladder]") {
  Ladder ladder;
  auto rung = ladder.kind("ladder.rung");
  // A rung along world X at height 1 m, 1 m long.
  const Constraint c = segment("ladder.rung", {0, 1, 0, 1, 1, 0});
  SECTION("on the rung: equality rows zero, inequality rows the distances to the ends") {
    const Eval e = evaluate(*rung, c, {0.3, 1.0, 0.0});
    CHECK(e.r(0) == Approx(0).margin(1e-15));
    CHECK(e.r(1) == Approx(0).margin(1e-15));
    CHECK(e.r(2) == Approx(0.3));
    CHECK(e.r(3) == Approx(0.7));
  }
  SECTION("off the line: the two orthogonal components make the distance") {
    const Eval e = evaluate(*rung, c, {0.3, 1.05, 0.02});
    CHECK(std::hypot(e.r(0), e.r(1)) == Approx(std::hypot(0.05, 0.02)));
    CHECK(e.r(2) == Approx(0.3));  // sliding along is free
  }
  SECTION("past B: the last inequality row is violated by the overshoot") {
    const Eval e = evaluate(*rung, c, {1.2, 1.0, 0.0});
    CHECK(e.r(3) == Approx(-0.2));
    CHECK(e.r(2) == Approx(1.2));
  }
  SECTION("a margin keeps the point inside both ends") {
    const Constraint m = segment("ladder.rung", {0, 1, 0, 1, 1, 0, 0.1});
    const Eval e = evaluate(*rung, m, {0.05, 1.0, 0.0});
    CHECK(e.r(2) == Approx(-0.05));
    CHECK(e.r(3) == Approx(0.85));
  }
}

TEST_CASE("ladder.rail: a slanted rail, default margin half a hand", "[ladder]") {
  Ladder ladder;
  auto rail = ladder.kind("ladder.rail");
  const Eigen::Vector3d a(0.2, 0.0, 0.5), b(0.2, 3.0, 1.5);  // leaning back 1 m over 3 m
  const Constraint c = segment("ladder.rail", {a.x(), a.y(), a.z(), b.x(), b.y(), b.z()});
  const double length = (b - a).norm();
  const Eigen::Vector3d u = (b - a) / length;
  const Eigen::Vector3d on = a + 1.0 * u;
  const Eval e = evaluate(*rail, c, on);
  CHECK(e.r.head<2>().norm() == Approx(0).margin(1e-12));
  CHECK(e.r(2) == Approx(1.0 - 0.04));
  CHECK(e.r(3) == Approx(length - 0.04 - 1.0));
  // 3 cm off the rail, perpendicular to it.
  const Eigen::Vector3d off = on + 0.03 * u.cross(Eigen::Vector3d::UnitX()).normalized();
  CHECK(evaluate(*rail, c, off).r.head<2>().norm() == Approx(0.03));
}

TEST_CASE("ladder kinds: analytic derivatives match finite differences", "[ladder]") {
  Ladder ladder;
  const std::vector<std::vector<double>> segments = {{0, 1, 0, 1, 1, 0},
                                                     {0.2, 0, 0.5, 0.2, 3, 1.5, 0.1},
                                                     {-0.3, 0.4, 0.1, 0.5, 0.45, -0.2},
                                                     {0, 0, 0, 0, 0, 2}};
  for (const char* name : {"ladder.rung", "ladder.rail"}) {
    auto kind = ladder.kind(name);
    for (const auto& params : segments) {
      const Constraint c = segment(name, params);
      REQUIRE_NOTHROW(kind->check(c));
      for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.9, 0.1), Eigen::Vector3d(-0.7, 1.4, 0.6)}) {
        const Eval e = evaluate(*kind, c, p);
        const double h = 1e-6;
        for (int axis = 0; axis < 3; ++axis) {
          const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
          const Eigen::VectorXd fd =
              (evaluate(*kind, c, p + step).r - evaluate(*kind, c, p - step).r) / (2 * h);
          CAPTURE(name, params, axis);
          for (int r = 0; r < 4; ++r) CHECK(e.dp(r, axis) == Approx(fd(r)).margin(1e-8));
        }
      }
    }
  }
}

TEST_CASE("ladder kinds refuse constraints that do not suit them", "[ladder]") {
  Ladder ladder;
  auto rung = ladder.kind("ladder.rung");
  CHECK_THROWS_WITH(rung->check(segment("ladder.rung", {0, 1, 0, 1, 1})),
                    Contains("test ladder.rung") && Contains("got 5 numbers"));
  CHECK_THROWS_WITH(rung->check(segment("ladder.rung", {0, 1, 0, 0, 1, 0})), Contains("coincide"));
  CHECK_THROWS_WITH(rung->check(segment("ladder.rung", {0, 1, 0, 1, 1, 0, 0.6})), Contains("margin"));
  CHECK_THROWS_WITH(rung->check(segment("ladder.rung", {0, 1, 0, 1, 1, 0, -0.1})), Contains("margin"));
  CHECK_THROWS_WITH(rung->check(segment("ladder.rung", {0, 1, 0, NAN, 1, 0})), Contains("finite"));
  // The rail's default margin needs a rail longer than a hand.
  CHECK_THROWS_WITH(ladder.kind("ladder.rail")->check(segment("ladder.rail", {0, 0, 0, 0, 0.05, 0})),
                    Contains("margin"));
  Constraint two = segment("ladder.rung", {0, 1, 0, 1, 1, 0});
  two.points.push_back(two.points[0]);
  CHECK_THROWS_WITH(rung->check(two), Contains("expects 1 point"));
  Constraint inequality = segment("ladder.rung", {0, 1, 0, 1, 1, 0});
  inequality.relation = kg::retarget::Relation::AtLeast;
  CHECK_THROWS_WITH(rung->check(inequality), Contains("relation must be equal"));
  Constraint two_frames = segment("ladder.rung", {0, 1, 0, 1, 1, 0});
  two_frames.samples = {{.frames = {1, 2}}};
  CHECK_THROWS_WITH(rung->check(two_frames), Contains("1 frame"));
  Constraint bad_sample = segment("ladder.rung", {0, 1, 0, 1, 1, 0});
  bad_sample.samples = {{.frames = {1}, .params = {1, 2, 3}}};
  CHECK_THROWS_WITH(rung->check(bad_sample), Contains("sample params"));
}
