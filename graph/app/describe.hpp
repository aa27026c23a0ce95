// What `kinegraph nodes` and `kinegraph dot` print.
//
//   print_nodes_text(std::cout, registry);
//   write_dot(std::cout, graph, registry);
#pragma once

#include <ostream>
#include <vector>

#include "kg/graph/graph.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/registry.hpp"

namespace kg::app {

// Every node type in name order: version, origin, doc, inputs and outputs with types, params
// with type, default (or "required"), range, choices and doc.
void print_nodes_text(std::ostream& os, const graph::Registry& registry);

// {"kinegraph": version, "plugin_abi": N, "plugins": [{"id","version","path","nodes","extensions"}],
//  "nodes": [{"type","version","doc","origin","inputs":[{"name","type","required","doc"}],
//             "outputs":[...], "params":[{"name","type","required","default","min","max","choices","doc"}]}]}
// Defaults are JSON values of the param's type (null when required); min/max null when unbounded.
void print_nodes_json(std::ostream& os, const graph::Registry& registry,
                      const std::vector<graph::LoadedPlugin>& plugins);

// Graphviz dot: one record per node (inputs left, id and type middle, outputs right), one edge
// per connection from output port to input port, labelled with the port type.
void write_dot(std::ostream& os, const graph::Graph& graph, const graph::Registry& registry);

}  // namespace kg::app
