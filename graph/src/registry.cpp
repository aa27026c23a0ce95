#include "kg/graph/registry.hpp"

#include <algorithm>
#include <cctype>
#include <set>

#include "kg/base/text.hpp"

namespace kg::graph {

namespace {

bool has_blank(const std::string& s) {
  return std::any_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c) || std::iscntrl(c); });
}

bool matches(ParamType type, const ParamValue& v) {
  switch (type) {
    case ParamType::Bool:
      return std::holds_alternative<bool>(v);
    case ParamType::Int:
      return std::holds_alternative<std::int64_t>(v);
    case ParamType::Float:
      return std::holds_alternative<double>(v);
    case ParamType::FloatList:
      return std::holds_alternative<std::vector<double>>(v);
    default:
      return std::holds_alternative<std::string>(v);
  }
}

// Authors write `0` for a float default or `1.0` for a list of one; accept what converts exactly,
// so that nodes can always `get<double>` a Float param.
ParamValue normalised_default(const ParamSpec& p) {
  const ParamValue& v = p.default_value;
  if (p.type == ParamType::Float && std::holds_alternative<std::int64_t>(v))
    return static_cast<double>(std::get<std::int64_t>(v));
  if (p.type == ParamType::Int && std::holds_alternative<double>(v)) {
    const double d = std::get<double>(v);
    if (d == std::floor(d) && std::abs(d) < 9.0e15) return static_cast<std::int64_t>(d);
  }
  if (p.type == ParamType::FloatList) {
    if (std::holds_alternative<double>(v)) return std::vector<double>{std::get<double>(v)};
    if (std::holds_alternative<std::int64_t>(v))
      return std::vector<double>{static_cast<double>(std::get<std::int64_t>(v))};
  }
  return v;
}

void check_spec(NodeSpec& spec, const std::string& origin) {
  const std::string who = "node type '" + spec.type + "' (" + origin + ")";
  auto check_ports = [&](const std::vector<PortSpec>& ports, const char* kind) {
    std::set<std::string> seen;
    for (const PortSpec& p : ports) {
      if (p.name.empty() || has_blank(p.name) || p.name.find('.') != std::string::npos)
        throw Error(who + ": " + kind + " port name '" + p.name +
                    "' must be non-empty, without blanks or dots");
      if (!seen.insert(p.name).second) throw Error(who + ": two " + kind + " ports named '" + p.name + "'");
      if (p.type.empty()) throw Error(who + ": " + kind + " port '" + p.name + "' has no type name");
    }
  };
  check_ports(spec.inputs, "input");
  check_ports(spec.outputs, "output");

  std::set<std::string> seen;
  for (ParamSpec& p : spec.params) {
    const std::string param = who + ": param '" + p.name + "'";
    if (p.name.empty() || has_blank(p.name))
      throw Error(who + ": param name '" + p.name + "' is empty or has blanks");
    if (!seen.insert(p.name).second) throw Error(who + ": two params named '" + p.name + "'");
    if (p.type == ParamType::Enum && p.choices.empty()) throw Error(param + ": an enum needs choices");
    if (p.min && p.max && *p.min > *p.max) throw Error(param + ": min is above max");
    if (p.required) continue;
    p.default_value = normalised_default(p);
    if (!matches(p.type, p.default_value))
      throw Error(param + ": default " + to_string(p.default_value) + " is not a " + to_string(p.type));
    if (p.type == ParamType::Enum) {
      const auto& s = std::get<std::string>(p.default_value);
      if (std::find(p.choices.begin(), p.choices.end(), s) == p.choices.end())
        throw Error(param + ": default '" + s + "' is not one of its choices");
    }
    auto in_range = [&](double x) { return (!p.min || x >= *p.min) && (!p.max || x <= *p.max); };
    bool ok = true;
    if (p.type == ParamType::Int) ok = in_range(static_cast<double>(std::get<std::int64_t>(p.default_value)));
    if (p.type == ParamType::Float) ok = in_range(std::get<double>(p.default_value));
    if (p.type == ParamType::FloatList)
      for (double x : std::get<std::vector<double>>(p.default_value)) ok = ok && in_range(x);
    if (!ok) throw Error(param + ": default " + to_string(p.default_value) + " is out of its range");
  }
}

// A pointer to `target` whose control block also holds `owner`; `target`'s storage goes first.
template <class T>
std::shared_ptr<const T> holding(std::shared_ptr<const T> target, std::shared_ptr<const void> owner) {
  if (!owner || !target) return target;
  struct Both {
    std::shared_ptr<const void> owner;
    std::shared_ptr<const T> target;
  };
  auto both = std::make_shared<const Both>(Both{std::move(owner), std::move(target)});
  return std::shared_ptr<const T>(both, both->target.get());
}

}  // namespace

Extension Extension::kept_alive_by(std::shared_ptr<const void> owner) const {
  Extension kept = *this;
  kept.object_ = holding(object_, std::move(owner));
  return kept;
}

void Registry::add_node(NodeType type, std::shared_ptr<const void> owner, std::string origin) {
  if (type.spec.type.empty() || has_blank(type.spec.type))
    throw Error("node type name '" + type.spec.type + "' from " + origin +
                " must be non-empty and without blanks");
  if (!type.create && !type.create_with_registry)
    throw Error("node type '" + type.spec.type + "' from " + origin + " has no factory");
  if (auto it = nodes_.find(type.spec.type); it != nodes_.end())
    throw Error("node type '" + type.spec.type + "' from " + origin + " is already registered by " +
                it->second.origin);
  check_spec(type.spec, origin);
  std::string name = type.spec.type;
  nodes_.emplace(std::move(name), NodeEntry{std::move(type), std::move(owner), std::move(origin)});
}

void Registry::add_extension(Extension extension, std::shared_ptr<const void> owner, std::string origin) {
  const std::string& interface = extension.interface_;
  const std::string& name = extension.name_;
  if (interface.empty() || name.empty())
    throw Error("extension '" + interface + "' / '" + name + "' from " + origin +
                " needs an interface and a name");
  if (!extension.object_)
    throw Error("extension " + interface + " '" + name + "' from " + origin + " has no factory");
  std::string key = interface + '\n' + name;
  if (auto it = extensions_.find(key); it != extensions_.end())
    throw Error("extension " + interface + " '" + name + "' from " + origin + " is already registered by " +
                it->second.origin);
  extensions_.emplace(std::move(key),
                      ExtensionEntry{std::move(extension), std::move(owner), std::move(origin)});
}

const NodeType* Registry::find_node(const std::string& type) const {
  auto it = nodes_.find(type);
  return it == nodes_.end() ? nullptr : &it->second.type;
}

const std::string& Registry::node_origin(const std::string& type) const {
  static const std::string unknown;
  auto it = nodes_.find(type);
  return it == nodes_.end() ? unknown : it->second.origin;
}

std::vector<std::string> Registry::node_type_names() const {
  std::vector<std::string> names;
  names.reserve(nodes_.size());
  for (const auto& [name, entry] : nodes_) names.push_back(name);
  return names;  // std::map keeps them sorted
}

NodePtr Registry::create_node(const std::string& type, const Params& params) const {
  auto it = nodes_.find(type);
  if (it == nodes_.end()) {
    std::string message = "unknown node type " + text::in_quotes(type);
    const std::string near = nearest_name(type, node_type_names());
    if (!near.empty()) message += "; did you mean " + text::in_quotes(near) + "?";
    throw Error(message);
  }
  const NodeType& made_as = it->second.type;
  std::unique_ptr<Node> made =
      made_as.create_with_registry ? made_as.create_with_registry(params, *this) : made_as.create(params);
  if (!made) throw Error("the factory of node type '" + type + "' (" + it->second.origin + ") made no node");
  if (!it->second.owner) return NodePtr(std::move(made));
  // The deleter runs the node's destructor (code in the plugin), then releases the library.
  return NodePtr(made.release(), [owner = it->second.owner](const Node* node) { delete node; });
}

std::shared_ptr<const void> Registry::node_owner(const std::string& type) const {
  auto it = nodes_.find(type);
  return it == nodes_.end() ? nullptr : it->second.owner;
}

std::shared_ptr<const void> Registry::find_extension(const std::string& interface,
                                                     const std::string& name) const {
  auto it = extensions_.find(interface + '\n' + name);
  if (it == extensions_.end() || it->second.extension.interface_ != interface) return nullptr;
  return holding(it->second.extension.object_, it->second.owner);
}

std::vector<std::string> Registry::extension_names(const std::string& interface) const {
  std::vector<std::string> names;
  for (const auto& [key, entry] : extensions_)
    if (entry.extension.interface_ == interface) names.push_back(entry.extension.name_);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace kg::graph
