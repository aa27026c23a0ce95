// Options::validate() of the retime area (DESIGN.md 15): a table of invalid settings per struct,
// each refused with std::invalid_argument naming the struct, the field and the value; the
// defaults pass; the node factories refuse a bad setting when the graph loads.
#include <catch2/catch.hpp>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/option_table.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/retime_clip.hpp"
#include "kg/retime/retimer.hpp"
#include "kg/retime/time_optimal.hpp"
#include "kg/retime/torque_limits.hpp"

using namespace kg;
using namespace kg::retime;
using Catch::Matchers::Contains;
using kg::test::check_option_table;
using kg::test::kInf;
using kg::test::kNaN;

namespace {

RetimeOptions with_duration() {
  RetimeOptions o;
  o.duration = 2;
  return o;
}

}  // namespace

TEST_CASE("HullOptions::validate refuses each field out of range") {
  check_option_table<HullOptions>(
      {}, {
              {"HullOptions.pddot_max = 0.0", [](auto& o) { o.pddot_max = 0; }},
              {"HullOptions.pdot2_max = inf", [](auto& o) { o.pdot2_max = kInf; }},
              {"HullOptions.tolerance = nan", [](auto& o) { o.tolerance = kNaN; }},
              {"HullOptions.initial_directions = 2", [](auto& o) { o.initial_directions = 2; }},
              {"HullOptions.max_lps = 8", [](auto& o) { o.max_lps = 8; }},
          });
}

TEST_CASE("TorqueLimitOptions::validate refuses each field out of range") {
  check_option_table<TorqueLimitOptions>(
      {}, {
              {"TorqueLimitOptions.margin = 0.0", [](auto& o) { o.margin = 0; }},
              {"TorqueLimitOptions.margin = inf", [](auto& o) { o.margin = kInf; }},
              {"TorqueLimitOptions.floor = -1.0", [](auto& o) { o.floor = -1; }},
              {"HullOptions.tolerance = 0.0", [](auto& o) { o.hulls.tolerance = 0; }},
          });
}

TEST_CASE("TimeOptimalOptions and RetimeOptions validate") {
  check_option_table<TimeOptimalOptions>(
      {}, {
              {"TimeOptimalOptions.point_tolerance = -0.1", [](auto& o) { o.point_tolerance = -0.1; }},
              {"TimeOptimalOptions.knot_spacing = 0.0", [](auto& o) { o.knot_spacing = 0; }},
          });
  check_option_table<RetimeOptions>(
      with_duration(),
      {
          {"RetimeOptions.duration = 0.0", [](auto& o) { o.duration = 0; }},
          {"RetimeOptions.duration = nan", [](auto& o) { o.duration = kNaN; }},
          {"RetimeOptions.knot_spacing = -0.1", [](auto& o) { o.knot_spacing = -0.1; }},
          {"RetimeOptions.knot_spacing = 1e-04", [](auto& o) { o.knot_spacing = 1e-4; }},  // 20,000 segments
          {"RetimeOptions.samples_per_frame = 0", [](auto& o) { o.samples_per_frame = 0; }},
          {"RetimeOptions.samples_per_frame = 1001",
           [](auto& o) { o.samples_per_frame = kMaxSamplesPerFrame + 1; }},
          {"RetimeOptions.max_iterations = 0", [](auto& o) { o.max_iterations = 0; }},
          {"RetimeOptions.function_tolerance = -1e-10", [](auto& o) { o.function_tolerance = -1e-10; }},
          {"RetimeOptions.gradient_tolerance = inf", [](auto& o) { o.gradient_tolerance = kInf; }},
      });
  CHECK_THROWS_WITH(RetimeOptions{}.validate(),
                    Contains("RetimeOptions.duration = 0.0"));  // no default duration
}

TEST_CASE("ClipRetimeOptions::validate: its own fields, time_optimal, and solve in Optimise mode") {
  ClipRetimeOptions good;
  good.solve = with_duration();
  check_option_table<ClipRetimeOptions>(
      good, {
                {"ClipRetimeOptions.alpha = -1.0", [](auto& o) { o.alpha = -1; }},
                {"ClipRetimeOptions.beta = nan", [](auto& o) { o.beta = kNaN; }},
                {"ClipRetimeOptions.flight_weight = -1.0", [](auto& o) { o.flight_weight = -1; }},
                {"ClipRetimeOptions.inside_tolerance = inf", [](auto& o) { o.inside_tolerance = kInf; }},
                {"TimeOptimalOptions.knot_spacing = 0.0", [](auto& o) { o.time_optimal.knot_spacing = 0; }},
                {"RetimeOptions.max_iterations = 0", [](auto& o) { o.solve.max_iterations = 0; }},
            });
  SECTION("the time-optimal mode needs no duration, only samples_per_frame of solve") {
    ClipRetimeOptions o;
    o.mode = RetimeMode::TimeOptimal;
    CHECK_NOTHROW(o.validate());
    o.solve.samples_per_frame = 0;
    CHECK_THROWS_WITH(o.validate(), Contains("RetimeOptions.samples_per_frame = 0"));
  }
}

TEST_CASE("FootContactOptions::validate refuses each field out of range") {
  check_option_table<FootContactOptions>(
      {},
      {
          {"FootContactOptions.heel_ratio = -0.1", [](auto& o) { o.heel_ratio = -0.1; }},
          {"FootContactOptions.width_ratio = 0.0", [](auto& o) { o.width_ratio = 0; }},
          {"FootContactOptions.support_acceleration = nan", [](auto& o) { o.support_acceleration = kNaN; }},
          {"FootplantOptions.hysteresis = 0.5", [](auto& o) { o.plants.hysteresis = 0.5; }},
      });
  FootContactOptions off;
  off.support_acceleration = 0;  // 0: off
  CHECK_NOTHROW(off.validate());
}

TEST_CASE("retime node factories refuse a bad setting when the graph loads") {
  const graph::Registry registry = test::registry_of(builtin_node_types());
  for (const char* type : {"retime.hulls", "retime.retime", "retime.contacts", "retime.torque_limits"}) {
    INFO(type << ": its defaults load");
    const graph::NodeType& t = test::node_type(registry, type);
    CHECK_NOTHROW(t.create(test::params_for(t.spec)));
  }
  const graph::NodeType& torque = test::node_type(registry, "retime.torque_limits");
  CHECK_NOTHROW(torque.create(test::params_for(torque.spec, {{"margin", 0.0}})));  // 0: the body's own limits
}
