// What the io area's node adapters share: the params every importer node declares for
// ImportOptions (import_options.hpp) and reading them back, and the motion formats
// (motion_format.hpp) as registry extensions of the interface kg.MotionFormat.
//
//   record.add_extension<io::MotionFormat>("glTF", gltf_format(), "glTF 2.0 skins");  // a plugin
//   io::MotionFormats formats = io::motion_formats_in(registry);    // what io.export_motion picks from
#pragma once

#include <string>
#include <vector>

#include "kg/graph/extension.hpp"
#include "kg/graph/node_spec.hpp"
#include "kg/graph/registry.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/motion/nodes.hpp"

// Registered under the format's name (MotionFormat::name, "BVH").
KG_DECLARE_INTERFACE(kg::io::MotionFormat, "kg.MotionFormat")

namespace kg::io {

// units (default `default_units`: auto or a unit name), up, fps.
std::vector<graph::ParamSpec> import_option_params(const std::string& default_units = "auto");
ImportOptions import_options_from(const graph::Params& params);

// builtin_motion_formats() as kg.MotionFormat extensions, each under its name.
std::vector<graph::Extension> builtin_motion_format_extensions();
// Every kg.MotionFormat extension of `registry`, by name.
MotionFormats motion_formats_in(const graph::Registry& registry);

}  // namespace kg::io
