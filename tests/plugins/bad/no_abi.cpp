// Exports an entry but no ABI version: the loader must refuse it without calling the entry.
#include <stdexcept>

#include "kg/graph/plugin_abi.hpp"

namespace {
kg::graph::PluginRecord entry() {
  throw std::logic_error("the entry of a plugin without ABI version was called");
}
}  // namespace

BOOST_DLL_ALIAS(entry, kg_plugin_entry)
