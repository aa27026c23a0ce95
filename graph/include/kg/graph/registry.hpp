// The one registry of node types and other extensions (constraint kinds, motion formats, ...).
// Built-in nodes and plugins register through the same calls (DESIGN.md 6). Entries from a
// plugin hold a shared_ptr to its library, so nothing made from it outlives the code behind it.
//
//   Registry registry;
//   registry.add_node(my_type);                       // built-in: no owner
//   auto node = registry.create_node("io.import_bvh", params);
//   registry.add_extension(Extension::make<ConstraintKind>("ladder.rung", kind, "a rung"));
//   std::shared_ptr<const ConstraintKind> k = registry.find<ConstraintKind>("ladder.rung");
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kg/graph/extension.hpp"
#include "kg/graph/node.hpp"

namespace kg::graph {

// A node created by the registry; holds its plugin's library (if any) until destroyed.
using NodePtr = std::shared_ptr<const Node>;

class Registry {
 public:
  // `owner` keeps the providing library loaded (null for built-ins); `origin` names it in
  // messages ("built-in" or the plugin's path). A type name already present is refused with
  // Error naming both origins.
  void add_node(NodeType type, std::shared_ptr<const void> owner = {}, std::string origin = "built-in");
  void add_extension(Extension extension, std::shared_ptr<const void> owner = {},
                     std::string origin = "built-in");

  const NodeType* find_node(const std::string& type) const;
  const std::string& node_origin(const std::string& type) const;
  std::vector<std::string> node_type_names() const;  // sorted

  // Throws Error for an unknown type, suggesting the nearest known name.
  NodePtr create_node(const std::string& type, const Params& params) const;
  // The owner of a node type's library (null for built-ins): values made by its nodes keep it.
  std::shared_ptr<const void> node_owner(const std::string& type) const;

  // The extension `name` of interface T (KG_DECLARE_INTERFACE); null when absent. The pointer
  // also keeps a plugin's library loaded.
  template <Interface T>
  std::shared_ptr<const T> find(const std::string& name) const {
    return std::static_pointer_cast<const T>(find_extension(InterfaceName<T>::value, name));
  }
  // The names of every extension of interface T, sorted.
  template <Interface T>
  std::vector<std::string> names() const {
    return extension_names(InterfaceName<T>::value);
  }

  // The type-erased layer under find<T> and names<T>, by interface name, for RunContext
  // implementations to forward (RunContext::find_extension) and for messages; null when absent
  // or of another interface. Nodes and plugins use find<T>.
  std::shared_ptr<const void> find_extension(const std::string& interface, const std::string& name) const;
  std::vector<std::string> extension_names(const std::string& interface) const;  // sorted

 private:
  struct NodeEntry {
    NodeType type;
    std::shared_ptr<const void> owner;
    std::string origin;
  };
  struct ExtensionEntry {
    Extension extension;
    std::shared_ptr<const void> owner;
    std::string origin;
  };
  std::map<std::string, NodeEntry> nodes_;
  std::map<std::string, ExtensionEntry> extensions_;  // key: interface + '\n' + name
};

}  // namespace kg::graph
