// Graph files with variables (kg/graph/yaml_io.hpp) under fuzzing, against every built-in node
// type and the graph tests' node types (tests/graph/test_nodes.hpp). Each variable the file
// declares required gets a value of its own, a file name a motion reader claims, so a fuzzed
// graph goes past its head into nodes, params and connections. Refused: a placed kg::Error. Accepted:
// every node built, every connection between nodes of the graph, a topological order of all
// nodes, a value for every variable, and no text longer than kMaxExpandedBytes.
#include <cstdint>
#include <map>
#include <string>

#include "../graph/test_nodes.hpp"
#include "fuzz_support.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/yaml_io.hpp"

namespace {

using kg::fuzz::require;

const kg::graph::Registry& registry() {
  static const kg::graph::Registry r = [] {
    kg::graph::Registry built;
    kg::register_builtin_nodes(built);
    kg_test::register_test_nodes(built);
    return built;
  }();
  return r;
}

void check_graph(const kg::graph::Graph& g) {
  for (const kg::graph::NodeInstance& n : g.nodes) require(n.node != nullptr, "node " + n.id + " not built");
  require(g.connection_ends().size() == g.connections.size(), "a connection without its ends");
  require(g.topological_order().size() == g.nodes.size(), "no order of every node");
  for (const kg::graph::Variable& v : g.variables) {
    const auto it = g.values.find(v.name);
    require(it != g.values.end(), "variable " + v.name + " has no value");
    require(it->second.size() <= kg::graph::kMaxExpandedBytes,
            "variable " + v.name + " over the expansion limit");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(kg::fuzz::text(data, size));
  kg::fuzz::expect_clean("fuzz.yaml", [&] {
    const auto document = kg::graph::GraphDocument::from_string(text, "fuzz.yaml");
    std::map<std::string, std::string> overrides;
    for (const kg::graph::Variable& v : document.variables())
      if (v.required) overrides[v.name] = "fuzz_" + v.name + ".bvh";
    check_graph(document.load(registry(), overrides));
  });
  return 0;
}
