// A plugin whose entry throws.
#include <stdexcept>

#include "kg/graph/plugin_abi.hpp"

namespace {
kg::graph::PluginRecord make_record() {
  throw std::runtime_error("deliberately thrown by the entry");
}
}  // namespace

KG_PLUGIN(make_record)
