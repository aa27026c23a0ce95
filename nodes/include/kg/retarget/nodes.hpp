// The retargeting's port types (DESIGN.md 4) and what its node adapters share, declared once.
// Maths code includes the area's own headers (target.hpp, spacetime.hpp, ...) only.
#pragma once

#include "kg/graph/extension.hpp"
#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/value.hpp"
#include "kg/motion/nodes.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/skeleton_map.hpp"
#include "kg/retarget/target.hpp"

KG_DECLARE_TYPE(kg::retarget::ConstraintSet, "kg.Constraints")
KG_DECLARE_TYPE(kg::retarget::KeySpacing, "kg.KeySpacing")
KG_DECLARE_TYPE(kg::retarget::Target, "kg.Target")
namespace kg::retarget {
// A skeleton map on a port, with the two skeletons its joint indices refer to.
struct SkeletonMapValue {
  SkeletonMap map;
  std::shared_ptr<const motion::Skeleton> source, target;
};
}  // namespace kg::retarget
KG_DECLARE_TYPE(kg::retarget::SkeletonMapValue, "kg.SkeletonMap")
// The constraint kinds of the solvers, built in or from plugins (registry extensions).
KG_DECLARE_INTERFACE(kg::retarget::ConstraintKind, "kg.ConstraintKind")

namespace kg::retarget {

// The kinds `set` names, looked up among a run's or a registry's kg.ConstraintKind extensions (as
// kinds_for in constraint_kinds.hpp).
ConstraintKindTable kinds_for(const ConstraintSet& set, const graph::RunContext& ctx);
ConstraintKindTable kinds_for(const ConstraintSet& set, const graph::Registry& registry);

// The built-in kinds as kg.ConstraintKind registry extensions, so that a registry lists and hands
// them out like plugin kinds.
std::vector<graph::Extension> builtin_constraint_kind_extensions();

// The node `retarget.per_frame_ik` (also listed by retarget_metrics_node_types).
graph::NodeType per_frame_ik_node_type();
// The node `retarget.at_rate` (listed by retarget_spacetime_node_types).
graph::NodeType at_rate_node_type();

}  // namespace kg::retarget
