// What a node type declares about itself; the graph loader checks every graph against it before
// anything runs (DESIGN.md 2), and `kinegraph nodes` prints it.
//
//   NodeSpec spec{"io.import_bvh", 1, "Reads a BVH file.",
//                 /*inputs*/ {},
//                 /*outputs*/ {{"motion", "kg.Motion", true, "the clip, metres, radians"}},
//                 /*params*/ {{"path", ParamType::InputPath, std::string{}, "the .bvh file", true}}};
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "kg/graph/params.hpp"

namespace kg::graph {

struct PortSpec {
  std::string name;
  std::string type;      // stable type name, e.g. "kg.Motion"
  bool required = true;  // inputs only: an unconnected required input is a validation error
  std::string doc;
  // Outputs only: a value set before the node failed still reaches the consumers of this port
  // (a solver's report, saying why it failed, for the sink that writes it); their other inputs
  // from the failed node make them skip as usual.
  bool kept_on_failure = false;
};

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::String;
  ParamValue default_value;  // ignored when required
  std::string doc;
  bool required = false;        // no default: the graph file must give it
  std::optional<double> min{};  // Int, Float, FloatList elements: inclusive bounds
  std::optional<double> max{};
  std::vector<std::string> choices{};  // Enum only
};

struct NodeSpec {
  std::string type;  // "stage.name", e.g. "io.import_bvh"
  int version = 1;
  std::string doc;
  std::vector<PortSpec> inputs{};  // {} lets designated initializers leave them out
  std::vector<PortSpec> outputs{};
  std::vector<ParamSpec> params{};
  // The node acts outside the run (a sink: writes files): the executor never takes another
  // node's results for it (DESIGN.md 13), however alike their type, params and inputs. A node
  // with an output_path param is taken to have side effects whatever this says.
  bool side_effects = false;

  // side_effects, or an output_path param.
  bool has_side_effects() const;

  const PortSpec* find_input(const std::string& name) const;
  const PortSpec* find_output(const std::string& name) const;
  const ParamSpec* find_param(const std::string& name) const;
};

}  // namespace kg::graph
