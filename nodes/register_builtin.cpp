#include "kg/builtin_nodes.hpp"
#include "kg/io/nodes.hpp"
#include "kg/retarget/nodes.hpp"

namespace kg {

std::vector<graph::NodeType> builtin_node_types() {
  std::vector<graph::NodeType> all;
  for (auto area :
       {motion_node_types, bvh_node_types, asf_amc_node_types, report_node_types, inspect_node_types,
        synth_node_types, retarget_target_node_types, retarget_map_node_types, retarget_constraint_node_types,
        retarget_spacetime_node_types, retarget_metrics_node_types, retime_body_node_types, retime_node_types,
        retime_contact_node_types})
    for (graph::NodeType& type : area()) all.push_back(std::move(type));
  return all;
}

std::vector<graph::Extension> builtin_extensions() {
  std::vector<graph::Extension> all = retarget::builtin_constraint_kind_extensions();
  for (graph::Extension& format : io::builtin_motion_format_extensions()) all.push_back(std::move(format));
  return all;
}

void register_builtin_nodes(graph::Registry& registry) {
  for (graph::NodeType& type : builtin_node_types()) registry.add_node(std::move(type));
  for (graph::Extension& extension : builtin_extensions()) registry.add_extension(std::move(extension));
}

}  // namespace kg
