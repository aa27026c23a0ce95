// A loaded graph: an immutable description (nodes with checked params, connections, plugin
// entries, variables), every item remembering where in the file it came from. Built by
// yaml_io.hpp's load_graph, which validates it completely against a Registry; the executor runs
// it any number of times.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "kg/base/error.hpp"
#include "kg/graph/params.hpp"
#include "kg/graph/registry.hpp"

namespace kg::graph {

struct PortRef {
  std::string node;
  std::string port;
  std::string to_string() const { return node + "." + port; }
};

struct Connection {
  PortRef from;  // an output
  PortRef to;    // an input
  SourceLocation where;
};

struct NodeInstance {
  std::string id;
  std::string type;
  Params params;  // checked against the type's spec, defaults filled in, variables substituted
  SourceLocation where;
  NodePtr node;  // built by the registry; shared by every run
};

struct Variable {
  std::string name;
  std::string default_value;  // meaningful when !required
  bool required = false;
  std::string doc;
  SourceLocation where;
};

struct Graph {
  std::filesystem::path file;
  std::string doc;
  std::vector<Variable> variables;            // as declared, in file order
  std::map<std::string, std::string> values;  // every variable's value used (defaults and --set)
  std::vector<std::string> plugins;           // `plugins:` entries, after variable substitution
  std::vector<NodeInstance> nodes;            // in file order
  std::vector<Connection> connections;

  const NodeInstance* find_node(const std::string& id) const;
  // For each connection in order, the indices in `nodes` of its from and to nodes. Throws Error
  // at the connection's place when it names a node not in the graph.
  std::vector<std::pair<std::size_t, std::size_t>> connection_ends() const;
  // Node indices in a topological order (stable: file order among ready nodes).
  std::vector<std::size_t> topological_order() const;
};

}  // namespace kg::graph
