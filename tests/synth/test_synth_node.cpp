#include <catch2/catch.hpp>

#include "kg/base/error.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/yaml_io.hpp"
#include "kg/motion/nodes.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;

namespace {

graph::Registry synth_registry() {
  graph::Registry r;
  for (graph::NodeType& t : synth_node_types()) r.add_node(std::move(t));
  return r;
}

const graph::Figure* figure(const graph::NodeRun& run, const std::string& key) {
  for (const auto& [k, v] : run.figures)
    if (k == key) return &v;
  return nullptr;
}

}  // namespace

TEST_CASE("motion.synthesize declares its signature", "[synth][node]") {
  const graph::Registry r = synth_registry();
  const graph::NodeType* t = r.find_node("motion.synthesize");
  REQUIRE(t != nullptr);
  const graph::NodeSpec& spec = t->spec;
  CHECK(spec.inputs.empty());
  REQUIRE(spec.outputs.size() == 2);
  CHECK(spec.find_output("motion")->type == "kg.Motion");
  CHECK(spec.find_output("skeleton")->type == "kg.Skeleton");
  const graph::ParamSpec* kind = spec.find_param("kind");
  REQUIRE(kind != nullptr);
  CHECK(kind->choices == std::vector<std::string>{"walk", "jump", "climb"});
  for (const char* name : {"steps", "speed", "stature", "fps", "jump_height", "jump_distance", "gravity",
                           "rung_spacing", "rail_half_width", "ladder_distance"}) {
    CAPTURE(name);
    const graph::ParamSpec* p = spec.find_param(name);
    REQUIRE(p != nullptr);
    CHECK_FALSE(p->doc.empty());
    CHECK(p->min.has_value());
    CHECK(p->max.has_value());
    CHECK_FALSE(p->required);
  }
  CHECK(*spec.find_param("speed")->min == synth::kSpeedRange.min);
  CHECK(std::get<double>(spec.find_param("gravity")->default_value) == 9.81);
}

TEST_CASE("motion.synthesize runs in a graph: walk and jump", "[synth][node]") {
  const graph::Registry r = synth_registry();
  const std::string text = R"(version: 1
nodes:
  walk: {type: motion.synthesize, params: {kind: walk, steps: 4, speed: 1.2, fps: 60}}
  jump: {type: motion.synthesize, params: {kind: jump, jump_height: 0.25, jump_distance: 0.5, gravity: 9.81}}
)";
  const graph::Graph g = graph::load_graph_from_string(text, "synth.yaml", r);
  const graph::RunResult result = graph::run_graph(g, r, {.jobs = 2});
  REQUIRE(result.ok);
  const auto& walk = result.outputs.at("walk.motion").get<motion::Motion>();
  const auto& skeleton = result.outputs.at("walk.skeleton").get<motion::Skeleton>();
  CHECK(walk.fps == 60);
  CHECK(walk.skeleton.get() == &skeleton);  // the same shared skeleton, not a copy
  CHECK(skeleton.find_joint("LeftToeBase") >= 0);
  // The node reproduces the free function exactly.
  const synth::Synthesis direct = synth::synthesize_walk({.steps = 4, .speed = 1.2, .fps = 60});
  REQUIRE(walk.values.rows() == direct.motion.values.rows());
  CHECK((walk.values - direct.motion.values).cwiseAbs().maxCoeff() == 0);
  for (const graph::NodeRun& run : result.nodes) {
    CAPTURE(run.id);
    REQUIRE(figure(run, "frames") != nullptr);
    REQUIRE(figure(run, "seconds") != nullptr);
    REQUIRE(figure(run, "plants") != nullptr);
    CHECK(std::get<std::int64_t>(*figure(run, "plants")) > 0);
    if (run.id == "walk") {
      CHECK(std::get<std::int64_t>(*figure(run, "steps")) == 4);
      CHECK(std::get<std::int64_t>(*figure(run, "frames")) == walk.frame_count());
    } else {
      REQUIRE(figure(run, "flight_time") != nullptr);
      const double flight = std::get<double>(*figure(run, "flight_time"));
      CHECK(flight > 2 * std::sqrt(2 * 0.25 / 9.81) * 0.8);
      CHECK(flight < 2 * std::sqrt(2 * 0.25 / 9.81) * 1.3);
    }
  }
}

TEST_CASE("motion.synthesize: bad params are refused before anything runs", "[synth][node]") {
  const graph::Registry r = synth_registry();
  auto load = [&](const std::string& params) {
    return graph::load_graph_from_string(
        "version: 1\nnodes:\n  s: {type: motion.synthesize, params: " + params + "}\n", "bad.yaml", r);
  };
  CHECK_NOTHROW(load("{kind: jump}"));
  CHECK_THROWS_WITH(load("{kind: hop}"), Catch::Contains("bad.yaml:3") && Catch::Contains("kind"));
  CHECK_THROWS_WITH(load("{speed: 9}"), Catch::Contains("bad.yaml:3") && Catch::Contains("speed"));
  CHECK_THROWS_WITH(load("{steps: 1}"), Catch::Contains("steps"));
  CHECK_THROWS_WITH(load("{steps: 2.5}"), Catch::Contains("steps"));
  CHECK_THROWS_WITH(load("{gravity: -9.81}"), Catch::Contains("gravity"));
  CHECK_THROWS_WITH(load("{stride: 1}"), Catch::Contains("stride"));
  // `steps` is foot landings for a walk (2 to 200) and rungs for a climb (1 to 60).
  CHECK_NOTHROW(load("{kind: climb, steps: 1}"));
  CHECK_THROWS_WITH(load("{kind: climb, steps: 61}"),
                    Catch::Contains("bad.yaml:3") && Catch::Contains("steps 61: a climb takes 1 to 60"));
  CHECK_THROWS_WITH(load("{kind: walk, steps: 1}"), Catch::Contains("steps 1: a walk takes 2 to 200"));
  CHECK_THROWS_WITH(load("{kind: climb, rung_spacing: 0.5}"), Catch::Contains("rung_spacing"));
  CHECK_THROWS_WITH(load("{kind: climb, ladder_distance: 0.1}"), Catch::Contains("ladder_distance"));
  CHECK_THROWS_WITH(load("{kind: climb, rail_half_width: 1}"), Catch::Contains("rail_half_width"));
}

TEST_CASE("motion.synthesize runs a climb: the free function's clip, its figures reported", "[synth][node]") {
  const graph::Registry r = synth_registry();
  const std::string text = R"(version: 1
nodes:
  climb: {type: motion.synthesize, params: {kind: climb, steps: 2, rung_spacing: 0.28, ladder_distance: 0.48, fps: 30}}
)";
  const graph::Graph g = graph::load_graph_from_string(text, "climb.yaml", r);
  const graph::RunResult result = graph::run_graph(g, r, {.jobs = 1});
  REQUIRE(result.ok);
  const auto& climb = result.outputs.at("climb.motion").get<motion::Motion>();
  const synth::Synthesis direct =
      synth::synthesize_climb({.rungs = 2, .rung_spacing = 0.28, .ladder_distance = 0.48, .fps = 30});
  REQUIRE(climb.values.rows() == direct.motion.values.rows());
  CHECK((climb.values - direct.motion.values).cwiseAbs().maxCoeff() == 0);
  REQUIRE(result.nodes.size() == 1);
  const graph::NodeRun& run = result.nodes.front();
  REQUIRE(figure(run, "holds") != nullptr);
  CHECK(std::get<std::int64_t>(*figure(run, "holds")) == static_cast<std::int64_t>(direct.holds.size()));
  CHECK(std::get<std::int64_t>(*figure(run, "rungs_climbed")) == 2);
  CHECK(std::get<double>(*figure(run, "max_arm_extension")) == direct.max_arm_extension);
}
