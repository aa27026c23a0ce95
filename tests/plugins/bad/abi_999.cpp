// A plugin built for another ABI: kg_plugin_abi_version returns 999. Its entry must never be
// called (it throws so that a loader that calls it anyway is caught by the test's message check).
#include <cstdint>
#include <stdexcept>

#include "kg/graph/plugin_abi.hpp"

namespace {
std::uint32_t abi_version() {
  return 999;
}
kg::graph::PluginRecord entry() {
  throw std::logic_error("the entry of a wrong-ABI plugin was called");
}
}  // namespace

BOOST_DLL_ALIAS(abi_version, kg_plugin_abi_version)
BOOST_DLL_ALIAS(entry, kg_plugin_entry)
