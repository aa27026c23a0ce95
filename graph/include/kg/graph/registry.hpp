// The one registry of node types and other extensions (constraint kinds, ...). Built-in nodes
// and plugins register through the same calls (DESIGN.md 6). Entries from a plugin hold a
// shared_ptr to its library, so nothing made from it outlives the code behind it.
//
//   Registry registry;
//   registry.add_node(my_type);                       // built-in: no owner
//   auto node = registry.create_node("io.import_bvh", params);
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kg/graph/node.hpp"

namespace kg::graph {

// A named factory of some interface graph/ does not know (`kg.ConstraintKind`, ...). The
// consumer casts `factory` to the interface it declared; `interface` guards the cast.
struct Extension {
  std::string interface;             // e.g. "kg.ConstraintKind"
  std::string name;                  // e.g. "ladder.rung"
  std::shared_ptr<const void> factory;
  std::string doc;
};

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

  // Null when absent or of another interface.
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
