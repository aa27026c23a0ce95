// The retime.hulls node: two nodes of a run with the same inputs and settings build the hulls
// once (graphs/retime.yaml's reference and hulls when nothing is edited); other settings, other
// input objects, or inputs released since, build their own.
#include <catch2/catch.hpp>

#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "kg/retime/nodes.hpp"
#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/motion/resample.hpp"
#include "kg/body/body_build.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;

namespace {

// retime.hulls' inputs for a synthesized walk at 30 Hz, each a value of its own.
std::map<std::string, graph::Value> walk_inputs() {
  const motion::Motion walk = motion::resample(synth::synthesize_walk({.steps = 2}).motion, 30);
  const body::BodyModel body = body::build_body_model(walk.skeleton, {}).body;
  return {{"body", graph::Value::make(body)},
          {"contacts", graph::Value::make(retime::detect_contacts(walk, {}))},
          {"torques", graph::Value::make(retime::path_torques(body, walk, retime::path_derivatives(walk)))}};
}

}  // namespace

TEST_CASE("retime.hulls nodes with the same inputs and settings share one build", "[retime][hulls][node]") {
  const graph::Registry registry = test::registry_of(retime_node_types());
  const std::map<std::string, graph::Value> inputs = walk_inputs();
  auto run = [&](std::map<std::string, graph::ParamValue> params,
                 const std::map<std::string, graph::Value>& in) {
    return test::run_node(registry, "retime.hulls", test::params_for(registry, "retime.hulls", params), in);
  };
  auto hulls_of = [](const test::NodeContext& ctx) { return &ctx.outputs.at("hulls").get<retime::Hulls>(); };

  const test::NodeContext first = run({}, inputs);
  CHECK_FALSE(std::get<bool>(first.figures.at("shared")));
  // The body's own gravity written out is the same setting: shared, not built again.
  const test::NodeContext same = run({{"gravity", std::vector<double>{9.81}}}, inputs);
  CHECK(std::get<bool>(same.figures.at("shared")));
  CHECK(same.logged("shared"));
  CHECK(hulls_of(same) == hulls_of(first));
  CHECK(&same.outputs.at("torques").get<retime::PathTorques>() ==
        &first.outputs.at("torques").get<retime::PathTorques>());
  CHECK(same.figures.at("feasible") == first.figures.at("feasible"));

  // Another gravity: its own hulls.
  const test::NodeContext lighter = run({{"gravity", std::vector<double>{5.0}}}, inputs);
  CHECK_FALSE(std::get<bool>(lighter.figures.at("shared")));
  CHECK(hulls_of(lighter) != hulls_of(first));
  CHECK(hulls_of(lighter)->gravity.y() == Approx(-5));
  // Equal contacts in another object: not taken for the same input.
  std::map<std::string, graph::Value> copied = inputs;
  copied["contacts"] = graph::Value::make(inputs.at("contacts").get<retime::Contacts>());
  const test::NodeContext copy = run({}, copied);
  CHECK_FALSE(std::get<bool>(copy.figures.at("shared")));
  CHECK(hulls_of(copy)->frames.size() == hulls_of(first)->frames.size());
}

TEST_CASE("retime.hulls builds again once the shared hulls are released", "[retime][hulls][node]") {
  const graph::Registry registry = test::registry_of(retime_node_types());
  const std::map<std::string, graph::Value> inputs = walk_inputs();
  const graph::Params params = test::params_for(registry, "retime.hulls", {});
  { const test::NodeContext gone = test::run_node(registry, "retime.hulls", params, inputs); }
  const test::NodeContext again = test::run_node(registry, "retime.hulls", params, inputs);
  CHECK_FALSE(std::get<bool>(again.figures.at("shared")));
}

TEST_CASE("retime.hulls nodes running at once share one build, and share its failure",
          "[retime][hulls][node]") {
  const graph::Registry registry = test::registry_of(retime_node_types());
  const std::map<std::string, graph::Value> inputs = walk_inputs();
  auto run_pair = [&](const graph::Params& params) {
    // Two threads as the executor runs independent nodes: whichever comes second waits for the
    // first's build (or finds it done).
    std::optional<test::NodeContext> a, b;
    std::string error_a, error_b;
    auto run = [&](std::optional<test::NodeContext>& out, std::string& error) {
      try {
        out = test::run_node(registry, "retime.hulls", params, inputs);
      } catch (const std::exception& e) {
        error = e.what();
      }
    };
    std::thread other([&] { run(b, error_b); });
    run(a, error_a);
    other.join();
    return std::make_tuple(std::move(a), std::move(b), error_a, error_b);
  };
  {
    const auto [a, b, error_a, error_b] = run_pair(test::params_for(registry, "retime.hulls", {}));
    REQUIRE(a.has_value());
    REQUIRE(b.has_value());
    CHECK(std::get<bool>(a->figures.at("shared")) != std::get<bool>(b->figures.at("shared")));
    CHECK(&a->outputs.at("hulls").get<retime::Hulls>() == &b->outputs.at("hulls").get<retime::Hulls>());
  }
  // The walk's torques model no segment, so a mass scale fails inside the build: both nodes
  // fail with its message.
  const auto [a, b, error_a, error_b] =
      run_pair(test::params_for(registry, "retime.hulls", {{"mass_scale", 2.0}}));
  CHECK_FALSE(a.has_value());
  CHECK_FALSE(b.has_value());
  CHECK_THAT(error_a, Catch::Contains("a mass scale needs the segment"));
  CHECK(error_b == error_a);
}
