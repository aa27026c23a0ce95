// The body area's port types (DESIGN.md 4), for the node adapters that pass body models.
#pragma once

#include "kg/body/body_model.hpp"
#include "kg/graph/value.hpp"
#include "kg/motion/nodes.hpp"

KG_DECLARE_TYPE(kg::body::BodyModel, "kg.BodyModel")
