// What the io area's node adapters share: the params every importer node declares for
// ImportOptions (import_options.hpp) and reading them back.
#pragma once

#include <string>
#include <vector>

#include "kg/graph/node_spec.hpp"
#include "kg/io/import_options.hpp"
#include "kg/motion/nodes.hpp"

namespace kg::io {

// units (default `default_units`: auto or a unit name), up, fps.
std::vector<graph::ParamSpec> import_option_params(const std::string& default_units = "auto");
ImportOptions import_options_from(const graph::Params& params);

}  // namespace kg::io
