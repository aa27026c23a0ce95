// The built-in node types, one function per area; register_builtin.cpp registers them all.
#pragma once

#include <vector>

#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"

namespace kg {

std::vector<graph::NodeType> motion_node_types();   // motion.resample, motion.frame_range (nodes/motion)
std::vector<graph::NodeType> bvh_node_types();      // io.import_bvh, io.export_bvh, io.export_motion (io)
std::vector<graph::NodeType> asf_amc_node_types();  // io.import_asf_amc, io.import_motion (nodes/io)
std::vector<graph::NodeType> report_node_types();   // io.write_report (nodes/io)
std::vector<graph::NodeType>
inspect_node_types();                             // motion.inspect (nodes/io: it names units as importers do)
std::vector<graph::NodeType> synth_node_types();  // motion.synthesize (nodes/synth)
// nodes/retarget: retarget.target, retarget.constraints_on_target, retarget.initial_estimate,
// retarget.key_spacing
std::vector<graph::NodeType> retarget_target_node_types();
std::vector<graph::NodeType> retarget_map_node_types();  // retarget.propose_map, retarget.write_map
// retarget.footplants, retarget.constraints, retarget.merge_constraints
std::vector<graph::NodeType> retarget_constraint_node_types();
std::vector<graph::NodeType> retarget_spacetime_node_types();  // retarget.spacetime
std::vector<graph::NodeType> retarget_metrics_node_types();    // retarget.per_frame_ik, retarget.metrics
std::vector<graph::NodeType> retime_body_node_types();         // retime.body_model (nodes/retime)
// retime.dynamics, retime.hulls, retime.retime, retime.write_curves, retime.write_forces
std::vector<graph::NodeType> retime_node_types();
std::vector<graph::NodeType> retime_contact_node_types();  // retime.contacts (nodes/retime)

// Every built-in node type (the lists above, in that order).
std::vector<graph::NodeType> builtin_node_types();
// Every built-in extension: the constraint kinds of the spacetime solver (kg.ConstraintKind) and
// the motion file formats (kg.MotionFormat: BVH, ASF/AMC).
std::vector<graph::Extension> builtin_extensions();
// Registers builtin_node_types() and builtin_extensions() through the same Registry API as
// plugins (tests use this; the CLI loads them as the kg_builtin_nodes module instead).
void register_builtin_nodes(graph::Registry& registry);

}  // namespace kg
