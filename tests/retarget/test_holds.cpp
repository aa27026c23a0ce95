// Holds between two characters: detection on two synthesized walkers side by side, their
// distance constraints, the retarget.holds node, constraints and metrics across characters, and
// a two-character solve that keeps a hand-hold while one walker shrinks.
#include <catch2/catch.hpp>

#include <limits>

#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/holds.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/retarget/target.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

// The same walk, the second walker `dx` metres to the first one's left (world +X) and, from
// frame `apart_from` on, drifting a further 1 m/s away.
std::pair<motion::Motion, motion::Motion> side_by_side(double dx, int apart_from = 1 << 30) {
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 3, .speed = 1.2, .stature = 1.75, .fps = 30});
  motion::Motion a = walk.motion, b = walk.motion;
  b.name = "walk2";
  for (int f = 0; f < b.frame_count(); ++f)
    b.values(f, 0) += dx + (f > apart_from ? (f - apart_from) / 30.0 : 0.0);
  return {a, b};
}

}  // namespace

TEST_CASE("holds: pairs of points that stay close, kept at the source distance") {
  // B walks 0.5 m to A's left, so A's left hand and B's right hand are the close pair (their
  // distance swings with the arms, within 0.45 m); both right hands stay 0.5 m apart.
  const auto [a, b] = side_by_side(0.5, 40);
  const HoldDetection d = detect_holds(a, b,
                                       {.points_a = {"LeftHand", "RightHand"},
                                        .points_b = {"RightHand"},
                                        .max_distance = 0.45,
                                        .hysteresis = 1.0});
  INFO("closest " << d.closest);
  REQUIRE(d.holds.size() == 1);
  const HoldSpan& h = d.holds.front();
  CHECK(d.points_a[static_cast<std::size_t>(h.point_a)].name == "LeftHand");
  CHECK(d.points_b[static_cast<std::size_t>(h.point_b)].name == "RightHand");
  CHECK(d.points_b[static_cast<std::size_t>(h.point_b)].point.character == 1);
  CHECK(h.first_frame == 0);
  CHECK(h.last_frame > 40);                   // B starts drifting away at frame 40
  CHECK(h.last_frame < a.frame_count() - 1);  // they walked apart

  const ConstraintSet set = hold_constraints(d);
  REQUIRE(set.constraints.size() == 1);
  const Constraint& c = set.constraints.front();
  CHECK(c.kind == "distance");
  CHECK(c.label == "LeftHand ~ RightHand hold 1");
  CHECK(set.character_count() == 2);
  CHECK(static_cast<int>(c.samples.size()) == h.last_frame - h.first_frame + 1);
  // The source meets its own holds exactly.
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  const std::vector<motion::Motion> both{a, b};
  CHECK(summarize_violations(set, kinds, both).worst() < 1e-9);

  // Nobody close: no holds, and the closest approach says how far.
  const auto [c1, c2] = side_by_side(3.0);
  const HoldDetection none = detect_holds(c1, c2, {.points_a = {"LeftHand"}, .points_b = {"RightHand"}});
  CHECK(none.holds.empty());
  CHECK(none.closest > 2.0);
}

TEST_CASE("holds: bad input") {
  const auto [a, b] = side_by_side(0.5);
  CHECK_THROWS_WITH(detect_holds(a, b, {.points_a = {"LeftHnd"}, .points_b = {"LeftHand"}}),
                    Catch::Contains("holds: unknown joint 'LeftHnd'") && Catch::Contains("LeftHand"));
  CHECK_THROWS_WITH(detect_holds(a, b, {.points_a = {}, .points_b = {"LeftHand"}}),
                    Catch::Contains("at least one point"));
  CHECK_THROWS_WITH(
      detect_holds(a, b, {.points_a = {"LeftHand"}, .points_b = {"LeftHand"}, .max_distance = 0}),
      Catch::Contains("max_distance"));
  motion::Motion shorter = b;
  shorter.values.conservativeResize(b.frame_count() - 5, Eigen::NoChange);
  CHECK_THROWS_WITH(detect_holds(a, shorter, {.points_a = {"LeftHand"}, .points_b = {"LeftHand"}}),
                    Catch::Contains("differ in length or rate"));
  CHECK_THROWS_WITH(
      detect_holds(a, b, {.points_a = {"LeftHand"}, .points_b = {"LeftHand"}, .hysteresis = 0.5}),
      Catch::Contains("hysteresis"));
  CHECK_THROWS_WITH(
      detect_holds(a, b, {.points_a = {"LeftHand"}, .points_b = {"LeftHand"}, .min_duration_s = -1}),
      Catch::Contains("min_duration_s"));
  motion::Motion broken = b;
  broken.values(3, 5) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS(detect_holds(a, broken, {.points_a = {"LeftHand"}, .points_b = {"LeftHand"}}));
}

TEST_CASE("holds: hysteresis keeps a hold through a brief parting, short holds are dropped") {
  // The close pair's distance swings between about 0 and 0.37 m with the arms.
  const auto [a, b] = side_by_side(0.5);
  const HoldOptions tight{
      .points_a = {"LeftHand"}, .points_b = {"RightHand"}, .max_distance = 0.3, .hysteresis = 1.0};
  const HoldDetection parted = detect_holds(a, b, tight);
  REQUIRE(parted.holds.size() >= 2);
  HoldOptions loose = tight;
  loose.hysteresis = 1.5;  // leave only beyond 0.45 m: never
  const HoldDetection kept = detect_holds(a, b, loose);
  REQUIRE(kept.holds.size() == 1);
  CHECK(kept.holds.front().first_frame == 0);
  CHECK(kept.holds.front().last_frame == a.frame_count() - 1);
  HoldOptions long_only = tight;
  long_only.min_duration_s = 100;
  CHECK(detect_holds(a, b, long_only).holds.empty());
}

TEST_CASE("two walkers in one solve: one shrinks, the hand-hold stays, the other's legs are frozen") {
  const auto [a, b] = side_by_side(0.5);
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  const graph::Registry registry = test::registry_of(retarget_constraint_node_types());

  // retarget.holds between them, retarget.constraints reading a file naming the second walker.
  test::NodeContext holds =
      test::run_node(registry, "retarget.holds",
                     test::params_for(registry, "retarget.holds",
                                      {{"points", std::string("LeftHand")},
                                       {"points2", std::string("RightHand")},
                                       {"max_distance", 0.5}}),
                     {{"motion", graph::Value::make(a)}, {"motion2", graph::Value::make(b)}});
  CHECK(std::get<std::int64_t>(holds.figures.at("holds")) == 1);
  const ConstraintSet hold_set = holds.outputs.at("constraints").get<ConstraintSet>();
  const ConstraintSet second_floor =
      read_constraints_string(R"(version: 1
constraints:
  - kind: region
    label: "walker 2 toe above floor"
    points: [{joint: RightToeBase, end_site: true, character: 1}]
    params: [-.inf, -0.001, -.inf, .inf, .inf, .inf]
    frames: [0, 10]
)",
                              "walker2.yaml", std::vector<motion::Motion>{a, b});
  CHECK(second_floor.constraints.front().points.front().character == 1);

  // Walker 1 shrinks to 90%; walker 2 may move only above the hips.
  const Target small = uniform_target(a.skeleton, 0.9);
  ConstraintSet set = constraints_on_target(hold_set, small, 0);
  merge_constraints(set, second_floor);
  motion::Motion m1 = a;
  m1.skeleton = small.skeleton;
  m1.values.leftCols(3) *= 0.9;
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  std::vector<bool> frozen(static_cast<std::size_t>(b.skeleton->channel_count()), false);
  for (int j = 0; j < b.skeleton->joint_count(); ++j) {
    const std::string& name = b.skeleton->joint(j).name;
    if (name == "Hips" || name.find("Leg") != std::string::npos || name.find("Foot") != std::string::npos ||
        name.find("Toe") != std::string::npos)
      for (std::size_t k = 0; k < b.skeleton->joint(j).channels.size(); ++k)
        frozen[static_cast<std::size_t>(b.skeleton->joint(j).first_channel) + k] = true;
  }
  problem.characters.push_back({.initial = b, .frozen = frozen});
  problem.constraints = &set;
  problem.kinds = [&](const std::string& n) { return kinds.find(n); };
  const std::vector<motion::Motion> before{m1, b};
  INFO("before: " << summarize_violations(set, kinds, before).worst());
  CHECK(summarize_violations(set, kinds, before).worst() > 0.01);
  const SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  CHECK(summarize_violations(set, kinds, r.motions).worst() < 1e-3);
  for (int c = 0; c < b.skeleton->channel_count(); ++c)
    if (frozen[static_cast<std::size_t>(c)])
      CHECK((r.motions[1].values.col(c) - b.values.col(c)).cwiseAbs().maxCoeff() == 0.0);

  // The metrics measure constraints across characters given the second result, and refuse them without.
  const RetargetMetrics m = compute_metrics(
      {.result = &r.motions[0], .result2 = &r.motions[1], .constraints = &set, .kinds = &kinds});
  CHECK(m.worst_violation_metres < 1e-3);
  CHECK_THROWS_WITH(compute_metrics({.result = &r.motions[0], .constraints = &set, .kinds = &kinds}),
                    Catch::Contains("second character"));
}
