// The retiming's port types (DESIGN.md 4), declared once for its node adapters.
#pragma once

#include "kg/body/nodes.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/value.hpp"
#include "kg/motion/nodes.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path_torques.hpp"
#include "kg/retime/timewarp.hpp"

KG_DECLARE_TYPE(kg::retime::Contacts, "kg.Contacts")
KG_DECLARE_TYPE(kg::retime::Hulls, "kg.Hulls")
KG_DECLARE_TYPE(kg::retime::PathTorques, "kg.PathTorques")
KG_DECLARE_TYPE(kg::retime::TimeWarp, "kg.TimeWarp")

namespace kg::retime {
// The node `retime.playback` (listed by retime_node_types).
graph::NodeType playback_node_type();
}  // namespace kg::retime
