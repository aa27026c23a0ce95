// Graph files. Format (version 1):
//
//   version: 1
//   doc: Converts a clip to BVH.
//   variables:                        # set with --set name=value; ${name} anywhere in a string
//     input:  {doc: "a .bvh or .amc file", required: true}
//     output: {doc: "the .bvh to write", default: "out/converted.bvh"}
//   plugins: [kg_lowpass]             # names or paths (see plugin_loader.hpp)
//   nodes:
//     src: {type: io.import_motion, params: {path: "${input}"}}
//     out: {type: io.export_bvh, params: {path: "${output}"}}
//   connections:
//     - {from: src.motion, to: out.motion}
//
// Everything is checked before anything runs; every Error names file:line:column and the names
// involved (unknown key by dotted path, unknown node type with the nearest name, unknown port,
// type mismatch "expected X, got Y from a.b", unconnected required input, two connections into
// one input, cycle listed, param of wrong type or out of range, undefined variable, unsupported
// version, an output path equal to an input path, a text over kMaxExpandedBytes after ${...}
// expansion). The YAML itself goes through kg::parse_yaml (duplicate keys and alias growth).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kg/graph/graph.hpp"
#include "kg/graph/registry.hpp"

namespace kg::graph {

inline constexpr int kGraphFormatVersion = 1;
// The longest text a variable default or a param may become once its ${...} are replaced
// (1 MiB): defaults that repeat one another nest exponentially, and are refused at this size.
inline constexpr std::size_t kMaxExpandedBytes = 1 << 20;

// One `plugins:` entry of a graph file, variables substituted, and where it is written.
struct PluginEntry {
  std::string entry;
  SourceLocation where;
};

// What `kinegraph validate` finds: every problem of the graph, and the required variables a run
// would need. A required variable given no value stands for an unknown value: the params it
// reaches are not checked, and the nodes holding them are not made.
struct GraphCheck {
  Graph graph;                  // as far as it could be read; runnable only when both lists are empty
  std::vector<Error> problems;  // in the order found (file order within each kind of check)
  std::vector<Variable> needed;
};

// A graph file read and parsed once (YAML, strictly: no duplicate key, bounded alias growth), for
// callers that need its plugins or variables before the graph: the CLI loads the plugins that
// provide its node types, and batch and tests/fuzz/fuzz_graph.cpp give values to its variables.
// Cheap to copy (the parsed document is shared, never changed). Throws Error as load_graph does.
class GraphDocument {
 public:
  static GraphDocument from_file(const std::filesystem::path& file);
  // `file_name` names the text in messages and is the graph's file.
  static GraphDocument from_string(const std::string& text, const std::string& file_name);

  // As read_graph_variables, read_graph_plugins and load_graph below, without parsing again.
  std::vector<Variable> variables() const;
  // With `allow_missing`, an entry naming a required variable that has no value is left out.
  std::vector<PluginEntry> plugins(const std::map<std::string, std::string>& overrides,
                                   bool allow_missing = false) const;
  Graph load(const Registry& registry, const std::map<std::string, std::string>& overrides = {}) const;
  // As load, collecting every problem rather than throwing at the first; also checks that each
  // input path given exists or is written by the graph (a run finds that when the node runs).
  GraphCheck check(const Registry& registry, const std::map<std::string, std::string>& overrides = {}) const;

 private:
  struct Parsed;
  explicit GraphDocument(std::shared_ptr<const Parsed> parsed);
  std::shared_ptr<const Parsed> parsed_;
};

// Reads the `plugins:` entries of a graph file (after substituting variables) without needing
// its node types: the CLI loads them before load_graph. Throws Error as load_graph does.
std::vector<PluginEntry> read_graph_plugins(const std::filesystem::path& file,
                                            const std::map<std::string, std::string>& overrides);

// The variables a graph file declares, in file order, none resolved (batch passes a graph only
// the variables it declares). Throws Error as load_graph does for a malformed head.
std::vector<Variable> read_graph_variables(const std::filesystem::path& file);
// The same for a graph's text; `file_name` names it in messages.
std::vector<Variable> read_graph_variables_from_string(const std::string& text, const std::string& file_name);

// Loads and validates. `overrides` are --set values; one naming no declared variable is an
// Error. Node objects are created through `registry`.
Graph load_graph(const std::filesystem::path& file, const Registry& registry,
                 const std::map<std::string, std::string>& overrides = {});
Graph load_graph_from_string(const std::string& text, const std::string& file_name, const Registry& registry,
                             const std::map<std::string, std::string>& overrides = {});

}  // namespace kg::graph
