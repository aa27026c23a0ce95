#include "kg/builtin_nodes.hpp"

namespace kg {

std::vector<graph::NodeType> builtin_node_types() {
  std::vector<graph::NodeType> all;
  for (auto area : {motion_node_types, bvh_node_types, asf_amc_node_types, synth_node_types})
    for (graph::NodeType& type : area()) all.push_back(std::move(type));
  return all;
}

void register_builtin_nodes(graph::Registry& registry) {
  for (graph::NodeType& type : builtin_node_types()) registry.add_node(std::move(type));
}

}  // namespace kg
