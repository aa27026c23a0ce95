// The one header a plugin needs. A plugin is a shared library exporting, through Boost.DLL,
//   kg_plugin_abi_version : std::uint32_t()      read first, must equal kPluginAbiVersion
//   kg_plugin_entry       : PluginRecord()       id, version, node types and extensions
// Both come from one macro:
//
//   static kg::graph::PluginRecord make_record() {
//     kg::graph::PluginRecord r{"kg.lowpass", "1.0.0"};
//     r.nodes.push_back(lowpass_node_type());
//     r.add_extension<kg::retarget::ConstraintKind>("ladder.rung", make_rung_kind(), "a rung");
//     return r;
//   }
//   KG_PLUGIN(make_record)
//
// The record crosses the library boundary as C++ (std::string, std::function): host and plugin
// must be built by the same compiler and standard library against the same kg::graph; the ABI
// version changes whenever these headers change layout. No static-initialiser registration.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <boost/dll/alias.hpp>

#include "kg/graph/extension.hpp"
#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"

namespace kg::graph {

// 3: typed extensions (extension.hpp) and NodeType::create_with_registry.
// 4: NodeSpec::side_effects and PortSpec::kept_on_failure (the executor's caching and sinks).
// 5: kg::io::ImportOptions::trim (a MotionFormat reader's options changed layout).
inline constexpr std::uint32_t kPluginAbiVersion = 5;

struct PluginRecord {
  std::string id;       // unique, e.g. "kg.lowpass"
  std::string version;  // the plugin's own version, e.g. "1.0.0"
  std::vector<NodeType> nodes{};
  std::vector<Extension> extensions{};

  // An extension of interface T (declared with KG_DECLARE_INTERFACE), e.g. a constraint kind or
  // a motion format; `object` may be of a class derived from T.
  template <Interface T>
  void add_extension(std::string name, std::type_identity_t<std::shared_ptr<const T>> object,
                     std::string doc = {}) {
    extensions.push_back(Extension::make<T>(std::move(name), std::move(object), std::move(doc)));
  }
};

using PluginAbiVersionFn = std::uint32_t();
using PluginEntryFn = PluginRecord();

inline constexpr const char* kPluginAbiSymbol = "kg_plugin_abi_version";
inline constexpr const char* kPluginEntrySymbol = "kg_plugin_entry";

}  // namespace kg::graph

#define KG_PLUGIN(record_function)                                       \
  namespace kg_plugin_exports {                                          \
  inline std::uint32_t abi_version() {                                   \
    return ::kg::graph::kPluginAbiVersion;                               \
  }                                                                      \
  inline ::kg::graph::PluginRecord entry() {                             \
    return record_function();                                            \
  }                                                                      \
  }                                                                      \
  BOOST_DLL_ALIAS(kg_plugin_exports::abi_version, kg_plugin_abi_version) \
  BOOST_DLL_ALIAS(kg_plugin_exports::entry, kg_plugin_entry)
