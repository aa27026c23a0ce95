// The seven built-in constraint kinds: values, inequality rows, analytic derivatives against
// central finite differences, check() errors; the kind table and lookups; violation summaries.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "../support/node_context.hpp"
#include "kg/graph/registry.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Constraint make(std::string kind, Relation relation, int points, int channels, std::vector<double> params) {
  Constraint c;
  c.kind = std::move(kind);
  c.label = "test " + c.kind;
  c.relation = relation;
  for (int i = 0; i < points; ++i)
    c.points.push_back({.character = 0, .joint = i, .local = Eigen::Vector3d::Zero()});
  for (int i = 0; i < channels; ++i) c.channels.push_back({.character = 0, .channel = i});
  c.params = std::move(params);
  Sample s;
  s.frames.assign(static_cast<std::size_t>(points + channels), 0);
  c.samples.push_back(s);
  return c;
}

struct Eval {
  Eigen::VectorXd r;
  Eigen::MatrixXd dp, dv;
};

Eval eval(const ConstraintKind& kind, const Constraint& c, const std::vector<Eigen::Vector3d>& pts,
          const std::vector<double>& vals) {
  REQUIRE(pts.size() == c.points.size());  // evaluate reads one value per point and channel
  REQUIRE(vals.size() == c.channels.size());
  Eval e;
  const int rows = kind.rows(c);
  e.r.setZero(rows);
  e.dp.setZero(rows, static_cast<Eigen::Index>(3 * pts.size()));
  e.dv.setZero(rows, static_cast<Eigen::Index>(vals.size()));
  kind.evaluate(c, c.params, pts, vals, e.r, e.dp, e.dv);
  return e;
}

// Analytic derivatives of `c` at (pts, vals) against central differences.
void check_derivatives(const ConstraintKind& kind, const Constraint& c, std::vector<Eigen::Vector3d> pts,
                       std::vector<double> vals) {
  INFO(c.kind << " " << to_string(c.relation));
  const Eval base = eval(kind, c, pts, vals);
  const double h = 1e-6;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      std::vector<Eigen::Vector3d> plus = pts, minus = pts;
      plus[i][a] += h;
      minus[i][a] -= h;
      const Eigen::VectorXd fd = (eval(kind, c, plus, vals).r - eval(kind, c, minus, vals).r) / (2 * h);
      const Eigen::VectorXd an = base.dp.col(static_cast<Eigen::Index>(3 * i) + a);
      INFO("point " << i << " axis " << a << "\nfd " << fd.transpose() << "\nan " << an.transpose());
      CHECK((fd - an).norm() <= 1e-6 * std::max(1.0, an.norm()));
    }
  for (std::size_t i = 0; i < vals.size(); ++i) {
    std::vector<double> plus = vals, minus = vals;
    plus[i] += h;
    minus[i] -= h;
    const Eigen::VectorXd fd = (eval(kind, c, pts, plus).r - eval(kind, c, pts, minus).r) / (2 * h);
    const Eigen::VectorXd an = base.dv.col(static_cast<Eigen::Index>(i));
    INFO("value " << i);
    CHECK((fd - an).norm() <= 1e-6 * std::max(1.0, an.norm()));
  }
}

std::vector<Eigen::Vector3d> random_points(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) out.emplace_back(u(rng), u(rng), u(rng));
  return out;
}

const ConstraintKindTable& table() {
  static const ConstraintKindTable t = ConstraintKindTable::builtin();
  return t;
}

}  // namespace

TEST_CASE("parameter_range: range rows, equality and one-sided forms") {
  const ConstraintKind& k = *table().find("parameter_range");
  Constraint range = make("parameter_range", Relation::Equal, 0, 2, {-0.5, 1.0});
  REQUIRE_NOTHROW(k.check(range));
  REQUIRE(k.rows(range) == 4);
  Eval e = eval(k, range, {}, {0.2, 1.5});
  CHECK(e.r[0] == Approx(0.7));  // 0.2 - (-0.5)
  CHECK(e.r[1] == Approx(0.8));  // 1.0 - 0.2
  CHECK(e.r[2] == Approx(2.0));
  CHECK(e.r[3] == Approx(-0.5));  // violated: above max
  for (int i = 0; i < 4; ++i) CHECK(k.is_inequality(range, i));

  Constraint lower = make("parameter_range", Relation::Equal, 0, 1, {-kInf, 1.0});
  REQUIRE(k.rows(lower) == 1);
  CHECK(eval(k, lower, {}, {0.25}).r[0] == Approx(0.75));

  Constraint eq = make("parameter_range", Relation::Equal, 0, 1, {0.3});
  CHECK_FALSE(k.is_inequality(eq, 0));
  CHECK(eval(k, eq, {}, {0.5}).r[0] == Approx(0.2));
  Constraint at_most = make("parameter_range", Relation::AtMost, 0, 1, {0.3});
  CHECK(k.is_inequality(at_most, 0));
  CHECK(eval(k, at_most, {}, {0.5}).r[0] == Approx(-0.2));

  for (const Constraint& c : {range, lower, eq, at_most}) {
    std::vector<double> values{0.2, 1.5};
    values.resize(c.channels.size());
    check_derivatives(k, c, {}, values);
  }
}

TEST_CASE("position and region: masked axes, inequalities, boxes") {
  const ConstraintKind& pos = *table().find("position");
  Constraint floor = make("position", Relation::Equal, 1, 0, {0, 0.1, 0, 0, 1, 0});
  REQUIRE(pos.rows(floor) == 1);
  CHECK(eval(pos, floor, {{3, 0.4, -2}}, {}).r[0] == Approx(0.3));
  Constraint all = make("position", Relation::Equal, 1, 0, {1, 2, 3});
  REQUIRE(pos.rows(all) == 3);
  const Eval e = eval(pos, all, {{1.5, 2, 2}}, {});
  CHECK(e.r[0] == Approx(0.5));
  CHECK(e.r[2] == Approx(-1));
  Constraint below = make("position", Relation::AtMost, 1, 0, {0, 1.0, 0, 0, 1, 0});
  CHECK(pos.is_inequality(below, 0));
  CHECK(eval(pos, below, {{0, 1.2, 0}}, {}).r[0] == Approx(-0.2));  // 1.2 is not at most 1.0

  const ConstraintKind& reg = *table().find("region");
  Constraint above = make("region", Relation::Equal, 1, 0, {-kInf, 0.0, -kInf, kInf, kInf, kInf});
  REQUIRE(reg.rows(above) == 1);
  CHECK(reg.is_inequality(above, 0));
  CHECK(eval(reg, above, {{5, -0.02, 1}}, {}).r[0] == Approx(-0.02));
  Constraint box = make("region", Relation::Equal, 1, 0, {0, 0, 0, 1, 2, 3});
  REQUIRE(reg.rows(box) == 6);
  const Eval b = eval(reg, box, {{0.5, 2.5, -1}}, {});
  CHECK(b.r.minCoeff() == Approx(-1.0));  // z below its min by 1
  CHECK(b.r[3] == Approx(-0.5));          // y above its max by 0.5

  std::mt19937 rng(1);
  for (int trial = 0; trial < 5; ++trial)
    for (const Constraint* c : {&floor, &all, &below, &above, &box}) {
      const ConstraintKind& k = c->kind == "position" ? pos : reg;
      check_derivatives(k, *c, random_points(rng, 1), {});
    }
}

TEST_CASE("same_place and follow_path: two points, masks, offsets") {
  const ConstraintKind& same = *table().find("same_place");
  Constraint skid = make("same_place", Relation::Equal, 2, 0, {1, 0, 1});
  skid.samples[0].frames = {10, 11};
  REQUIRE_NOTHROW(same.check(skid));
  REQUIRE(same.rows(skid) == 2);
  const Eval e = eval(same, skid, {{1, 0, 2}, {1.5, 3, 1}}, {});
  CHECK(e.r[0] == Approx(0.5));
  CHECK(e.r[1] == Approx(-1));
  Constraint any = make("same_place", Relation::Equal, 2, 0, {});
  CHECK(same.rows(any) == 3);

  const ConstraintKind& follow = *table().find("follow_path");
  Constraint f = make("follow_path", Relation::Equal, 2, 0, {0, 0.5, 0});
  REQUIRE(follow.rows(f) == 3);
  const Eval ef = eval(follow, f, {{1, 2, 3}, {1, 1, 3}}, {});
  CHECK(ef.r[1] == Approx(0.5));  // 2 - 1 - 0.5
  CHECK(ef.r[0] == Approx(0));
  Constraint fm = make("follow_path", Relation::AtLeast, 2, 0, {0, 0, 0, 0, 1, 0});
  CHECK(follow.rows(fm) == 1);
  CHECK(follow.is_inequality(fm, 0));

  std::mt19937 rng(2);
  for (int trial = 0; trial < 5; ++trial) {
    check_derivatives(same, skid, random_points(rng, 2), {});
    check_derivatives(same, any, random_points(rng, 2), {});
    check_derivatives(follow, f, random_points(rng, 2), {});
    check_derivatives(follow, fm, random_points(rng, 2), {});
  }
}

TEST_CASE("distance: equality and one-sided, guarded at coincident points") {
  const ConstraintKind& k = *table().find("distance");
  Constraint eq = make("distance", Relation::Equal, 2, 0, {0.5});
  CHECK(eval(k, eq, {{0, 0, 0}, {0, 0.3, 0.4}}, {}).r[0] == Approx(0.0).margin(1e-9));
  CHECK(eval(k, eq, {{0, 0, 0}, {0, 0, 1}}, {}).r[0] == Approx(0.5));
  Constraint at_least = make("distance", Relation::AtLeast, 2, 0, {0.5});
  CHECK(eval(k, at_least, {{0, 0, 0}, {0, 0, 0.2}}, {}).r[0] == Approx(-0.3));
  Constraint at_most = make("distance", Relation::AtMost, 2, 0, {0.5});
  CHECK(eval(k, at_most, {{0, 0, 0}, {0, 0, 0.2}}, {}).r[0] == Approx(0.3));
  // Coincident points: finite value and derivatives.
  const Eval z = eval(k, eq, {{1, 1, 1}, {1, 1, 1}}, {});
  CHECK(std::isfinite(z.r[0]));
  CHECK(z.dp.allFinite());
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial)
    for (const Constraint* c : {&eq, &at_least, &at_most})
      check_derivatives(k, *c, random_points(rng, 2), {});
}

TEST_CASE("orientation: unit direction rows and the angle inequality") {
  const ConstraintKind& k = *table().find("orientation");
  Constraint eq = make("orientation", Relation::Equal, 2, 0, {0, 2, 0});  // normalised to +Y
  REQUIRE(k.rows(eq) == 3);
  const Eval up = eval(k, eq, {{1, 1, 1}, {1, 3, 1}}, {});
  CHECK(up.r.norm() == Approx(0).margin(1e-9));
  const Eval side = eval(k, eq, {{0, 0, 0}, {2, 0, 0}}, {});
  CHECK(side.r[0] == Approx(1));
  CHECK(side.r[1] == Approx(-1));
  Constraint cone = make("orientation", Relation::AtMost, 2, 0, {0, 1, 0, std::numbers::pi / 4});
  REQUIRE(k.rows(cone) == 1);
  CHECK(k.is_inequality(cone, 0));
  // 30 degrees off +Y: inside a 45-degree cone.
  const double a = std::numbers::pi / 6;
  const Eval in = eval(k, cone, {{0, 0, 0}, {std::sin(a), std::cos(a), 0}}, {});
  CHECK(in.r[0] == Approx(std::cos(a) - std::cos(std::numbers::pi / 4)));
  CHECK(in.r[0] > 0);
  const Eval out = eval(k, cone, {{0, 0, 0}, {1, 0.2, 0}}, {});
  CHECK(out.r[0] < 0);
  Constraint away = make("orientation", Relation::AtLeast, 2, 0, {0, 1, 0, std::numbers::pi / 4});
  CHECK(eval(k, away, {{0, 0, 0}, {1, 0.2, 0}}, {}).r[0] > 0);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 5; ++trial)
    for (const Constraint* c : {&eq, &cone, &away}) check_derivatives(k, *c, random_points(rng, 2), {});
}

TEST_CASE("check() refuses shapes that do not suit the kind, naming the label") {
  struct Bad {
    Constraint c;
    const char* message;
  };
  std::vector<Bad> bad;
  bad.push_back({make("position", Relation::Equal, 2, 0, {0, 0, 0}), "expects 1 point, got 2"});
  bad.push_back(
      {make("position", Relation::Equal, 1, 0, {0, 0}), "expects params [x y z] or [x y z mx my mz], got 2"});
  bad.push_back({make("position", Relation::Equal, 1, 0, {0, 0, 0, 0, 0, 0}), "the mask fixes no axis"});
  bad.push_back({make("position", Relation::Equal, 1, 0, {0, 0, 0, 2, 0, 0}), "mask entry must be 0 or 1"});
  bad.push_back({make("position", Relation::Equal, 1, 0, {0, kInf, 0}), "param 1 is infinite"});
  bad.push_back({make("parameter_range", Relation::Equal, 0, 0, {0, 1}), "expects at least 1 channel"});
  bad.push_back({make("parameter_range", Relation::Equal, 0, 1, {1, 0}), "min > max"});
  bad.push_back({make("parameter_range", Relation::Equal, 0, 1, {-kInf, kInf}), "both bounds are infinite"});
  bad.push_back({make("parameter_range", Relation::AtLeast, 0, 1, {0, 1}), "takes relation equal"});
  bad.push_back({make("region", Relation::Equal, 1, 0, {0, 0, 0, -1, 1, 1}), "min bound exceeds its max"});
  bad.push_back({make("region", Relation::Equal, 1, 0, {-kInf, -kInf, -kInf, kInf, kInf, kInf}),
                 "every bound is infinite"});
  bad.push_back({make("same_place", Relation::Equal, 1, 0, {}), "expects 2 points, got 1"});
  bad.push_back({make("same_place", Relation::AtLeast, 2, 0, {}), "relation equal only"});
  bad.push_back({make("distance", Relation::Equal, 2, 0, {-1}), "distance is negative"});
  bad.push_back({make("distance", Relation::Equal, 2, 0, {std::nan("")}), "param 0 is NaN"});
  bad.push_back({make("orientation", Relation::Equal, 2, 0, {0, 0, 0}), "direction is zero"});
  bad.push_back({make("orientation", Relation::AtMost, 2, 0, {0, 1, 0}), "[dx dy dz max_angle_rad]"});
  Constraint no_samples = make("distance", Relation::Equal, 2, 0, {1});
  no_samples.samples.clear();
  bad.push_back({no_samples, "has no samples"});
  Constraint short_sample = make("distance", Relation::Equal, 2, 0, {1});
  short_sample.samples[0].frames = {3};
  bad.push_back({short_sample, "a sample has 1 frames, expected 2"});
  Constraint weight = make("distance", Relation::Equal, 2, 0, {1});
  weight.weight = 0;
  bad.push_back({weight, "weight must be positive"});
  Constraint pattern = make("region", Relation::Equal, 1, 0, {-kInf, 0, -kInf, kInf, kInf, kInf});
  pattern.samples[0].params = {0, 0, -kInf, kInf, kInf, kInf};
  bad.push_back({pattern, "differs from the constraint's in being finite"});
  for (const Bad& b : bad) {
    INFO(b.c.kind << ": " << b.message);
    const ConstraintKind& k = *table().find(b.c.kind);
    try {
      k.check(b.c);
      FAIL("no error");
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      CHECK_THAT(what, Catch::Contains(b.message));
      CHECK_THAT(what, Catch::Contains("constraint 'test " + b.c.kind + "'"));
    }
  }
}

namespace {
// A kind a plugin could provide: a point's height equals params[0] (one row).
class HeightKind final : public ConstraintKind {
 public:
  std::string name() const override { return "test.height"; }
  std::string doc() const override { return "height"; }
  void check(const Constraint&) const override {}
  int rows(const Constraint&) const override { return 1; }
  bool is_inequality(const Constraint&, int) const override { return false; }
  void evaluate(const Constraint&, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    r[0] = points[0].y() - params[0];
    dp(0, 1) = 1;
  }
};

}  // namespace

TEST_CASE("kind table: built-ins, duplicates, lookups through extensions, unknown kinds") {
  const ConstraintKindTable t = ConstraintKindTable::builtin();
  CHECK(t.names() == std::vector<std::string>{"distance", "follow_path", "orientation", "parameter_range",
                                              "position", "region", "same_place"});
  CHECK(t.find("nope") == nullptr);
  for (const std::string& name : t.names()) CHECK(t.find(name)->name() == name);
  ConstraintKindTable copy = t;
  copy.add(std::make_shared<HeightKind>());
  CHECK(copy.find("test.height") != nullptr);
  CHECK(t.find("test.height") == nullptr);  // the copy did not touch the original
  CHECK_THROWS_WITH(copy.add(std::make_shared<HeightKind>()), Catch::Contains("'test.height' is already"));
  CHECK_THROWS_WITH(copy.add(t.find_shared("position")), Catch::Contains("'position' is already"));

  ConstraintSet set;
  set.constraints.push_back(make("position", Relation::Equal, 1, 0, {0, 0, 0}));
  set.constraints.push_back(make("test.height", Relation::Equal, 1, 0, {0.5}));
  set.constraints.back().label = "my height";

  // Through a registry holding the built-ins as extensions and the plugin-like kind.
  graph::Registry registry;
  for (graph::Extension& e : builtin_constraint_kind_extensions()) registry.add_extension(std::move(e));
  CHECK(registry.names<ConstraintKind>().size() == 7);
  SECTION("unknown kind: the message lists known kinds") {
    try {
      kinds_for(set, registry);
      FAIL("no error");
    } catch (const std::invalid_argument& e) {
      CHECK(std::string(e.what()) ==
            "constraint 'my height': unknown kind 'test.height' (known: distance, follow_path, orientation, "
            "parameter_range, position, region, same_place)");
    }
    set.constraints.back().kind = "positon";
    CHECK_THROWS_WITH(kinds_for(set, registry), Catch::Contains("unknown kind 'positon'") &&
                                                    Catch::Contains("did you mean 'position'?"));
    // A context without a registry finds no extension either.
    CHECK_THROWS_WITH(
        kinds_for(set, [](const std::string&) { return std::shared_ptr<const ConstraintKind>(); }),
        Catch::Contains("unknown kind 'positon'"));
  }
  SECTION("found through the registry and through a RunContext") {
    registry.add_extension(graph::Extension::make<ConstraintKind>(
        "test.height", std::make_shared<HeightKind>(), "a point's height"));
    const ConstraintKindTable a = kinds_for(set, registry);
    REQUIRE(a.find("test.height") != nullptr);
    CHECK(a.names().size() == 8);
    test::NodeContext ctx;
    ctx.registry = &registry;
    const ConstraintKindTable b = kinds_for(set, ctx);
    const ConstraintKind* h = b.find("test.height");
    REQUIRE(h != nullptr);
    const Eval e = eval(*h, set.constraints[1], {{0, 2, 0}}, {});
    CHECK(e.r[0] == Approx(1.5));
    CHECK_NOTHROW(check_constraints(set, b));
  }
  SECTION("an extension registered under another name than its own is refused") {
    registry.add_extension(
        graph::Extension::make<ConstraintKind>("test.height", t.find_shared("distance"), "wrong"));
    CHECK_THROWS_WITH(kinds_for(set, registry), Catch::Contains("calls itself 'distance'"));
  }
}

TEST_CASE("evaluation on motions and violation summaries") {
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 60});
  const motion::Motion& m = walk.motion;
  const std::span<const motion::Motion> chars(&m, 1);
  const PoseCache poses(chars);
  REQUIRE(poses.frame_count(0) == m.frame_count());

  // The synthesizer's plants as fixed positions: met by the source to rounding.
  ConstraintSet plants;
  for (const synth::FootPlant& p : walk.plants) {
    Constraint c;
    c.kind = "position";
    c.label = p.name();
    c.points = {{.character = 0, .joint = p.joint, .local = p.local}};
    c.params = {p.world.x(), p.world.y(), p.world.z()};
    for (int f = p.first_frame; f <= p.last_frame; ++f) c.samples.push_back({.frames = {f}});
    plants.constraints.push_back(c);
  }
  REQUIRE(!plants.constraints.empty());
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  REQUIRE_NOTHROW(check_constraints(plants, kinds));
  ViolationSummary v = summarize_violations(plants, kinds, poses);
  REQUIRE(v.kinds.size() == 1);
  CHECK(v.kinds[0].kind == "position");
  CHECK(v.kinds[0].worst < 1e-6);
  CHECK(v.kinds[0].violated_rows == 0);
  CHECK(v.kinds[0].counted_rows == v.kinds[0].rows);

  // Move one plant's target 5 cm up: the worst is 5 cm, at that plant.
  plants.constraints[0].params[1] += 0.05;
  v = summarize_violations(plants, kinds, chars);
  CHECK(v.find("position")->worst == Approx(0.05).margin(1e-6));
  CHECK(v.find("position")->worst_label == plants.constraints[0].label);
  CHECK(v.find("position")->worst_frame >= walk.plants[0].first_frame);  // every frame of it is off by 5 cm
  CHECK(v.find("position")->worst_frame <= walk.plants[0].last_frame);
  CHECK(v.find("position")->violated_rows == static_cast<int>(plants.constraints[0].samples.size()));
  CHECK(v.worst() == Approx(0.05).margin(1e-6));

  // Inequalities count only when violated: the toe tip above a floor at y = 0 (met, up to the
  // synthesizer's exact plants) and above y = 0.5 m (violated at every frame).
  Constraint above;
  above.kind = "region";
  above.label = "toe above";
  above.points = {{.character = 0, .joint = walk.figure.toe[0], .local = walk.figure.toe_tip_local}};
  above.params = {-kInf, -1e-9, -kInf, kInf, kInf, kInf};
  for (int f = 0; f < m.frame_count(); ++f) above.samples.push_back({.frames = {f}});
  ConstraintSet ineq;
  ineq.constraints.push_back(above);
  v = summarize_violations(ineq, kinds, poses);
  CHECK(v.find("region")->worst == 0);
  CHECK(v.find("region")->counted_rows == 0);
  CHECK(v.find("region")->mean == 0);
  ineq.constraints[0].params[1] = 0.5;
  v = summarize_violations(ineq, kinds, poses);
  CHECK(v.find("region")->counted_rows == m.frame_count());
  Eigen::VectorXd r;
  double worst = 0, sum = 0;
  for (const Sample& s : ineq.constraints[0].samples) {
    evaluate_sample(*kinds.find("region"), ineq.constraints[0], s, poses, r);
    worst = std::max(worst, -r[0]);
    sum += -r[0];
  }
  CHECK(v.find("region")->worst == Approx(worst));
  CHECK(v.find("region")->mean == Approx(sum / m.frame_count()));
  CHECK(worst >= 0.5 - 1e-6);

  // Out-of-range frames and joints are reported with the label.
  Constraint late = above;
  late.label = "late";
  late.samples = {{.frames = {m.frame_count()}}};
  CHECK_THROWS_WITH(
      evaluate_sample(*kinds.find("region"), late, late.samples[0], poses, r),
      Catch::Contains("constraint 'late'") && Catch::Contains("frame " + std::to_string(m.frame_count())));
  late.points[0].character = 1;
  late.samples = {{.frames = {0}}};
  CHECK_THROWS_WITH(evaluate_sample(*kinds.find("region"), late, late.samples[0], poses, r),
                    Catch::Contains("character 1"));

  CHECK(plants.character_count() == 1);
  ConstraintSet two;
  two.constraints.push_back(make("distance", Relation::Equal, 2, 0, {1}));
  two.constraints[0].points[1].character = 1;
  CHECK(two.character_count() == 2);
}
