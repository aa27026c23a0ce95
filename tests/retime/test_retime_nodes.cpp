// The retime.hulls node in the executor: two nodes of a run with the same params and inputs build
// the hulls once, the second taking the first's results (same_as; graphs/retime.yaml's reference
// and hulls when nothing is edited); other settings, inputs from other nodes, or another run,
// build their own.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "kg/body/body_build.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/yaml_io.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/nodes.hpp"
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

// A node type outputting `value` on its port `out` (the graph's inputs, made in the test).
graph::NodeType value_node(const std::string& type, const graph::Value& value) {
  class ValueNode final : public graph::Node {
   public:
    explicit ValueNode(graph::Value v) : v_(std::move(v)) {}
    void run(graph::RunContext& ctx) const override { ctx.set_output("out", v_); }

   private:
    graph::Value v_;
  };
  return {
      graph::NodeSpec{type, 1, "a value made by the test", {}, {{"out", value.type_name(), true, ""}}, {}},
      [value](const graph::Params&) { return std::make_unique<ValueNode>(value); }};
}

// retime.hulls' types, and test.body, test.contacts, test.contacts_copy (equal contacts in
// another object) and test.torques outputting walk_inputs().
graph::Registry hulls_registry() {
  graph::Registry registry = test::registry_of(retime_node_types());
  const std::map<std::string, graph::Value> in = walk_inputs();
  registry.add_node(value_node("test.body", in.at("body")));
  registry.add_node(value_node("test.contacts", in.at("contacts")));
  registry.add_node(
      value_node("test.contacts_copy", graph::Value::make(in.at("contacts").get<retime::Contacts>())));
  registry.add_node(value_node("test.torques", in.at("torques")));
  return registry;
}

// Graph text: the inputs and, per entry, a retime.hulls node `id` with `params` whose contacts
// come from `contacts`.
std::string hulls_graph(const std::vector<std::array<std::string, 3>>& hulls) {
  std::string text =
      "version: 1\nnodes:\n  body: {type: test.body}\n  contacts: {type: test.contacts}\n"
      "  contacts_copy: {type: test.contacts_copy}\n  torques: {type: test.torques}\n";
  std::string wires = "connections:\n";
  for (const auto& [id, params, contacts] : hulls) {
    text += "  " + id + ": {type: retime.hulls, params: {" + params + "}}\n";
    wires += "  - {from: body.out, to: " + id + ".body}\n  - {from: " + contacts + ".out, to: " + id +
             ".contacts}\n  - {from: torques.out, to: " + id + ".torques}\n";
  }
  return text + wires;
}

const graph::NodeRun& run_of(const graph::RunResult& r, const std::string& id) {
  for (const graph::NodeRun& n : r.nodes)
    if (n.id == id) return n;
  throw std::logic_error("no node " + id);
}

graph::RunOptions quiet(int jobs) {
  return {.jobs = jobs, .on_log = [](const std::string&, const std::string&) {}};
}

}  // namespace

TEST_CASE("retime.hulls nodes with the same params and inputs share one build", "[retime][hulls][node]") {
  const graph::Registry registry = hulls_registry();
  const graph::Graph g = graph::load_graph_from_string(hulls_graph({{"first", "", "contacts"},
                                                                    {"same", "", "contacts"},
                                                                    {"lighter", "gravity: 5", "contacts"},
                                                                    {"copy", "", "contacts_copy"}}),
                                                       "hulls.yaml", registry);
  std::vector<std::pair<std::string, std::string>> logs;
  graph::RunOptions options = quiet(1);
  options.on_log = [&](const std::string& id, const std::string& message) { logs.emplace_back(id, message); };
  const graph::RunResult r = graph::run_graph(g, registry, options);
  REQUIRE(r.ok);
  auto hulls_of = [&](const std::string& id) { return &r.outputs.at(id + ".hulls").get<retime::Hulls>(); };

  CHECK(run_of(r, "first").same_as.empty());
  CHECK(run_of(r, "same").same_as == "first");
  CHECK(
      std::find(logs.begin(), logs.end(),
                std::make_pair(
                    std::string("same"),
                    std::string(
                        "same_as: first (the same type, params and inputs: its results, not run again)"))) !=
      logs.end());
  CHECK(hulls_of("same") == hulls_of("first"));
  CHECK(&r.outputs.at("same.torques").get<retime::PathTorques>() ==
        &r.outputs.at("first.torques").get<retime::PathTorques>());
  CHECK(run_of(r, "same").figures == run_of(r, "first").figures);

  // Another gravity: its own hulls.
  CHECK(run_of(r, "lighter").same_as.empty());
  CHECK(hulls_of("lighter") != hulls_of("first"));
  CHECK(hulls_of("lighter")->gravity.y() == Approx(-5));
  // Equal contacts from another node: not taken for the same input.
  CHECK(run_of(r, "copy").same_as.empty());
  CHECK(hulls_of("copy") != hulls_of("first"));
  CHECK(hulls_of("copy")->frames.size() == hulls_of("first")->frames.size());
}

TEST_CASE("retime.hulls builds again in another run", "[retime][hulls][node]") {
  const graph::Registry registry = hulls_registry();
  const graph::Graph g =
      graph::load_graph_from_string(hulls_graph({{"first", "", "contacts"}}), "one.yaml", registry);
  const graph::RunResult a = graph::run_graph(g, registry, quiet(1));
  const graph::RunResult b = graph::run_graph(g, registry, quiet(1));
  REQUIRE(a.ok);
  REQUIRE(b.ok);
  CHECK(run_of(b, "first").same_as.empty());
  CHECK(&a.outputs.at("first.hulls").get<retime::Hulls>() !=
        &b.outputs.at("first.hulls").get<retime::Hulls>());
}

TEST_CASE("retime.hulls nodes ready at once share one build, and share its failure",
          "[retime][hulls][node]") {
  const graph::Registry registry = hulls_registry();
  {
    const graph::Graph g = graph::load_graph_from_string(
        hulls_graph({{"a", "", "contacts"}, {"b", "", "contacts"}}), "pair.yaml", registry);
    const graph::RunResult r = graph::run_graph(g, registry, quiet(2));
    REQUIRE(r.ok);
    CHECK(run_of(r, "b").same_as == "a");
    CHECK(&r.outputs.at("a.hulls").get<retime::Hulls>() == &r.outputs.at("b.hulls").get<retime::Hulls>());
  }
  // The walk's torques model no segment, so a mass scale fails inside the build: both nodes
  // fail with its message.
  const graph::Graph g = graph::load_graph_from_string(
      hulls_graph({{"a", "mass_scale: 2", "contacts"}, {"b", "mass_scale: 2", "contacts"}}), "fail.yaml",
      registry);
  const graph::RunResult r = graph::run_graph(g, registry, quiet(2));
  CHECK_FALSE(r.ok);
  CHECK(run_of(r, "a").status == graph::NodeStatus::Failed);
  CHECK(run_of(r, "b").status == graph::NodeStatus::Failed);
  CHECK_THAT(run_of(r, "a").message, Catch::Contains("a mass scale needs the segment"));
  CHECK(run_of(r, "b").message == run_of(r, "a").message);
  CHECK(run_of(r, "b").same_as == "a");
}
