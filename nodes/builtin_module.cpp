// The module through which the kinegraph CLI meets the built-in nodes: the same plugin record
// and loader as any plugin, so graph/ never includes nodes/ (DESIGN.md, "The house").
#include "kg/builtin_nodes.hpp"
#include "kg/graph/plugin_abi.hpp"

namespace {

kg::graph::PluginRecord builtin_record() {
  return kg::graph::PluginRecord{"kg.builtin", "0.1.0", kg::builtin_node_types(), kg::builtin_extensions()};
}

}  // namespace

KG_PLUGIN(builtin_record)
