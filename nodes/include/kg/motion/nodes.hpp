// The motion area's port types (DESIGN.md 4), declared once for every node adapter and plugin
// that passes skeletons and clips between nodes. Maths code includes kg/motion/motion.hpp only.
//
//   graph::Value v = graph::Value::make(motion);       // a kg.Motion
//   const motion::Motion& m = v.get<motion::Motion>();
#pragma once

#include "kg/graph/value.hpp"
#include "kg/motion/motion.hpp"

KG_DECLARE_TYPE(kg::motion::Skeleton, "kg.Skeleton")
KG_DECLARE_TYPE(kg::motion::Motion, "kg.Motion")
