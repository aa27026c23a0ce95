// The built-in node types, one function per area; register_builtin.cpp registers them all.
#pragma once

#include <vector>

#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"

namespace kg {

std::vector<graph::NodeType> motion_node_types();  // motion.resample, ... (nodes/motion)
std::vector<graph::NodeType> bvh_node_types();     // io.import_bvh, io.export_bvh (nodes/io)
std::vector<graph::NodeType> asf_amc_node_types(); // io.import_asf_amc, io.import_motion (nodes/io)
std::vector<graph::NodeType> synth_node_types();   // motion.synthesize (nodes/synth)

// Every built-in node type (the four lists above, in that order).
std::vector<graph::NodeType> builtin_node_types();
// Registers builtin_node_types() through the same Registry API as plugins (tests use this; the
// CLI loads them as the kg_builtin_nodes module instead).
void register_builtin_nodes(graph::Registry& registry);

}  // namespace kg
