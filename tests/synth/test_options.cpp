// WalkOptions, JumpOptions and ClimbOptions::validate() (DESIGN.md 15): a table of invalid
// settings per struct, each refused with the message the synthesizers gave before (option,
// value, range); motion.synthesize checks the chosen figure's options when the graph loads.
#include <catch2/catch.hpp>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/option_table.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::synth;
using Catch::Matchers::Contains;
using kg::test::check_option_table;
using kg::test::kInf;
using kg::test::kNaN;

TEST_CASE("WalkOptions, JumpOptions and ClimbOptions::validate refuse each field out of range") {
  check_option_table<WalkOptions>({
      {"synthesize_walk: steps 1", [](auto& o) { o.steps = 1; }},
      {"synthesize_walk: speed 3 m/s", [](auto& o) { o.speed = 3; }},
      {"synthesize_walk: stature nan m", [](auto& o) { o.stature = kNaN; }},
      {"synthesize_walk: fps 5 frames/s", [](auto& o) { o.fps = 5; }},
  });
  check_option_table<JumpOptions>({
      {"synthesize_jump: height 0.7 m", [](auto& o) { o.height = 0.7; }},
      {"synthesize_jump: distance -0.1 m", [](auto& o) { o.distance = -0.1; }},
      {"synthesize_jump: stature 3 m", [](auto& o) { o.stature = 3; }},
      {"synthesize_jump: fps 2000 frames/s", [](auto& o) { o.fps = 2000; }},
      {"synthesize_jump: gravity 0 m/s^2", [](auto& o) { o.gravity = 0; }},
  });
  check_option_table<ClimbOptions>({
      {"synthesize_climb: rungs 0", [](auto& o) { o.rungs = 0; }},
      {"synthesize_climb: rung_spacing 0.5 m", [](auto& o) { o.rung_spacing = 0.5; }},
      {"synthesize_climb: rail_half_width 0.1 m", [](auto& o) { o.rail_half_width = 0.1; }},
      {"synthesize_climb: ladder_distance 1 m", [](auto& o) { o.ladder_distance = 1; }},
      {"synthesize_climb: stature 1 m", [](auto& o) { o.stature = 1; }},
      {"synthesize_climb: fps 9 frames/s", [](auto& o) { o.fps = 9; }},
  });
  CHECK_THROWS_WITH(synthesize_walk({.steps = 1}), Contains("synthesize_walk: steps 1"));
}

TEST_CASE("motion.synthesize checks the chosen figure's options when the graph loads") {
  const graph::Registry registry = test::registry_of(synth_node_types());
  const graph::NodeType& type = test::node_type(registry, "motion.synthesize");
  for (const char* kind : {"walk", "jump", "climb"})
    CHECK_NOTHROW(type.create(test::params_for(type.spec, {{"kind", std::string(kind)}})));
}
