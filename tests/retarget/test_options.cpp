// Options::validate() of the retarget area (DESIGN.md 15): a table of invalid settings per
// struct, each refused with std::invalid_argument naming the struct, the field and the value;
// the defaults and the settings the graphs use pass; the library functions and the node
// factories refuse a bad setting before any work.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/option_table.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/footplants.hpp"
#include "kg/retarget/holds.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/per_frame_ik.hpp"
#include "kg/retarget/spacetime.hpp"

using namespace kg;
using namespace kg::retarget;
using Catch::Matchers::Contains;
using kg::test::check_option_table;
using kg::test::kInf;
using kg::test::kNaN;

TEST_CASE("SpacetimeOptions::validate refuses each field out of range") {
  check_option_table<SpacetimeOptions>({
      {"SpacetimeOptions.epsilon = 0.0", [](auto& o) { o.epsilon = 0; }},
      {"SpacetimeOptions.epsilon = nan", [](auto& o) { o.epsilon = kNaN; }},
      {"SpacetimeOptions.epsilon = inf", [](auto& o) { o.epsilon = kInf; }},
      {"SpacetimeOptions.equality_tolerance = -0.001", [](auto& o) { o.equality_tolerance = -1e-3; }},
      {"SpacetimeOptions.inequality_tolerance = 0.0", [](auto& o) { o.inequality_tolerance = 0; }},
      {"SpacetimeOptions.max_iterations = -1", [](auto& o) { o.max_iterations = -1; }},
      {"SpacetimeOptions.initial_damping = -1.0", [](auto& o) { o.initial_damping = -1; }},
      {"SpacetimeOptions.damping_decrease = 0.0", [](auto& o) { o.damping_decrease = 0; }},
      {"SpacetimeOptions.damping_decrease = 2.0", [](auto& o) { o.damping_decrease = 2; }},
      {"SpacetimeOptions.damping_increase = 0.5", [](auto& o) { o.damping_increase = 0.5; }},
      {"SpacetimeOptions.min_damping = -1e-08", [](auto& o) { o.min_damping = -1e-8; }},
      {"SpacetimeOptions.max_damping = 1e-09", [](auto& o) { o.max_damping = 1e-9; }},
      {"SpacetimeOptions.max_damping = inf", [](auto& o) { o.max_damping = kInf; }},
      {"SpacetimeOptions.armijo = 1.0", [](auto& o) { o.armijo = 1; }},
      {"SpacetimeOptions.line_search_shrink = 1.0", [](auto& o) { o.line_search_shrink = 1; }},
      {"SpacetimeOptions.line_search_steps = 0", [](auto& o) { o.line_search_steps = 0; }},
      {"SpacetimeOptions.working_set_resolves = -1", [](auto& o) { o.working_set_resolves = -1; }},
      {"SpacetimeOptions.working_set_release = nan", [](auto& o) { o.working_set_release = kNaN; }},
      {"SpacetimeOptions.min_step = -1.0", [](auto& o) { o.min_step = -1; }},
      {"SpacetimeOptions.min_decrease = 1.0", [](auto& o) { o.min_decrease = 1; }},
      {"SpacetimeOptions.min_decrease_short = -0.1", [](auto& o) { o.min_decrease_short = -0.1; }},
      {"SpacetimeOptions.stuck_ratio = 1.5", [](auto& o) { o.stuck_ratio = 1.5; }},
      {"SpacetimeOptions.stuck_decrease = 1.0", [](auto& o) { o.stuck_decrease = 1; }},
      {"SpacetimeOptions.stall_window = 0", [](auto& o) { o.stall_window = 0; }},
      {"SpacetimeOptions.stall_ratio = -0.5", [](auto& o) { o.stall_ratio = -0.5; }},
  });
  SECTION("the edges of the ranges pass: no iterations, no damping, no re-solves, no stopping tests") {
    SpacetimeOptions o;
    o.max_iterations = 0;
    o.initial_damping = o.min_damping = 0;
    o.damping_decrease = 1;
    o.working_set_resolves = 0;
    o.working_set_release = 0;
    o.min_step = o.min_decrease = o.min_decrease_short = o.stuck_decrease = 0;
    o.stuck_ratio = o.stall_ratio = 1;
    CHECK_NOTHROW(o.validate());
  }
}

TEST_CASE("solve_spacetime and linearize_spacetime validate their options first") {
  SpacetimeProblem problem;  // no characters: the options are checked before the problem
  problem.options.damping_increase = 0.5;
  CHECK_THROWS_WITH(solve_spacetime(problem), Contains("SpacetimeOptions.damping_increase = 0.5"));
  problem.characters.emplace_back();
  CHECK_THROWS_WITH(linearize_spacetime(problem, Eigen::VectorXd()),
                    Contains("SpacetimeOptions.damping_increase = 0.5"));
}

TEST_CASE("PerFrameIkOptions::validate refuses each field out of range") {
  check_option_table<PerFrameIkOptions>({
      {"PerFrameIkOptions.epsilon = -1.0", [](auto& o) { o.epsilon = -1; }},
      {"PerFrameIkOptions.epsilon = nan", [](auto& o) { o.epsilon = kNaN; }},
      {"PerFrameIkOptions.max_iterations = 0", [](auto& o) { o.max_iterations = 0; }},
      {"PerFrameIkOptions.tolerance = -0.001", [](auto& o) { o.tolerance = -1e-3; }},
      {"PerFrameIkOptions.tolerance = inf", [](auto& o) { o.tolerance = kInf; }},
  });
  PerFrameIkOptions zero;
  zero.epsilon = zero.tolerance = 0;
  CHECK_NOTHROW(zero.validate());
}

TEST_CASE("HoldOptions::validate refuses each field out of range") {
  HoldOptions good;
  good.points_a = {"lHand"};
  good.points_b = {"rHand"};
  check_option_table<HoldOptions>(
      good, {
                {"HoldOptions.points_a = []", [](auto& o) { o.points_a.clear(); }},
                {"HoldOptions.points_b = []", [](auto& o) { o.points_b.clear(); }},
                {"HoldOptions.max_distance = 0.0", [](auto& o) { o.max_distance = 0; }},
                {"HoldOptions.max_distance = inf", [](auto& o) { o.max_distance = kInf; }},
                {"HoldOptions.hysteresis = 0.9", [](auto& o) { o.hysteresis = 0.9; }},
                {"HoldOptions.min_duration_s = -0.1", [](auto& o) { o.min_duration_s = -0.1; }},
            });
  good.min_duration_s = 0;
  CHECK_NOTHROW(good.validate());
}

TEST_CASE("KeySpacingOptions::validate refuses each field out of range") {
  check_option_table<KeySpacingOptions>({
      {"KeySpacingOptions.threshold = 0.0", [](auto& o) { o.threshold = 0; }},
      {"KeySpacingOptions.threshold = 1.0", [](auto& o) { o.threshold = 1; }},
      {"KeySpacingOptions.threshold = nan", [](auto& o) { o.threshold = kNaN; }},
      {"KeySpacingOptions.spacing = -1", [](auto& o) { o.spacing = -1; }},
  });
  KeySpacingOptions groups;
  groups.groups = "not a group";
  CHECK_THROWS_WITH(groups.validate(), Contains("KeySpacingOptions.groups = 'not a group'"));
  groups.groups = "";
  groups.spacing = 0;  // 0: automatic
  CHECK_NOTHROW(groups.validate());
}

TEST_CASE("InitialEstimateOptions and PlantConstraintOptions validate") {
  check_option_table<InitialEstimateOptions>({
      {"InitialEstimateOptions.smooth_seconds = -0.1", [](auto& o) { o.smooth_seconds = -0.1; }},
      {"InitialEstimateOptions.smooth_seconds = inf", [](auto& o) { o.smooth_seconds = kInf; }},
  });
  InitialEstimateOptions none{.smooth_seconds = 0};  // 0: no smoothing
  CHECK_NOTHROW(none.validate());
  check_option_table<PlantConstraintOptions>({
      {"PlantConstraintOptions.weight = 0.0", [](auto& o) { o.weight = 0; }},
      {"PlantConstraintOptions.weight = nan", [](auto& o) { o.weight = kNaN; }},
  });
}

TEST_CASE("retarget node factories refuse a bad setting when the graph loads") {
  const graph::Registry registry = test::registry_of(builtin_node_types());
  struct Case {
    const char* type;
    std::map<std::string, graph::ParamValue> given;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"retarget.holds", {{"points", std::string("")}}, "HoldOptions.points_a = []"},
      {"retarget.holds", {{"points2", std::string(" , ")}}, "HoldOptions.points_b = []"},
      {"retarget.key_spacing", {{"groups", std::string("Left*")}}, "KeySpacingOptions.groups = 'Left*'"},
  };
  for (const Case& c : cases) {
    INFO(c.type << ": " << c.message);
    const graph::NodeType& type = test::node_type(registry, c.type);
    CHECK_THROWS_WITH(type.create(test::params_for(type.spec, c.given)), Contains(c.message));
  }
  for (const char* type : {"retarget.spacetime", "retarget.per_frame_ik", "retarget.holds",
                           "retarget.footplants", "retarget.key_spacing", "retarget.initial_estimate"}) {
    INFO(type << ": its defaults load");
    const graph::NodeType& t = test::node_type(registry, type);
    CHECK_NOTHROW(t.create(test::params_for(t.spec)));
  }
}
