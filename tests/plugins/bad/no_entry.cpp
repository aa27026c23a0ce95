// Exports the ABI version and nothing else: not a plugin.
#include <cstdint>

#include "kg/graph/plugin_abi.hpp"

namespace {
std::uint32_t abi_version() {
  return kg::graph::kPluginAbiVersion;
}
}  // namespace

BOOST_DLL_ALIAS(abi_version, kg_plugin_abi_version)
