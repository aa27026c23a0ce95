#include "describe.hpp"

#include <cctype>
#include <cmath>
#include <sstream>
#include <string>

#include "kg/base/json.hpp"
#include "kg/graph/plugin_abi.hpp"

namespace kg::app {
namespace {

using graph::ParamSpec;
using graph::PortSpec;
using kg::JsonWriter;

// Words of `text` on lines of at most `width` characters, each starting with `indent`.
void write_wrapped(std::ostream& os, const std::string& text, const std::string& indent,
                   std::size_t width = 100) {
  std::istringstream words(text);
  std::string word, line;
  while (words >> word) {
    if (!line.empty() && indent.size() + line.size() + 1 + word.size() > width) {
      os << indent << line << '\n';
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) os << indent << line << '\n';
}

std::string bound(double value) {
  if (std::isinf(value)) return value < 0 ? "-inf" : "inf";
  std::ostringstream os;
  os << value;
  return os.str();
}

std::string range_text(const ParamSpec& p) {
  if (!p.min && !p.max) return "";
  std::ostringstream os;
  os << '[' << (p.min ? bound(*p.min) : "-inf") << ", " << (p.max ? bound(*p.max) : "inf") << ']';
  return os.str();
}

void print_ports(std::ostream& os, const char* title, const std::vector<PortSpec>& ports, bool inputs) {
  if (ports.empty()) return;
  os << "  " << title << ":\n";
  for (const PortSpec& port : ports) {
    os << "    " << port.name << ": " << port.type;
    if (inputs && !port.required) os << " (optional)";
    if (!inputs && port.kept_on_failure) os << " (kept on failure)";
    os << '\n';
    if (!port.doc.empty()) write_wrapped(os, port.doc, "        ");
  }
}

void json_ports(JsonWriter& w, const char* key, const std::vector<PortSpec>& ports, bool inputs) {
  w.key(key);
  w.begin_array();
  for (const PortSpec& port : ports) {
    w.begin_object();
    w.field("name", port.name);
    w.field("type", port.type);
    if (inputs) w.field("required", port.required);
    if (!inputs) w.field("kept_on_failure", port.kept_on_failure);
    w.field("doc", port.doc);
    w.end_object();
  }
  w.end_array();
}

// Record labels treat {}|<> as structure; quotes and backslashes end or escape the string.
std::string record_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '{' || c == '}' || c == '|' || c == '<' || c == '>' || c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + '"';
}

// Record field names: letters, digits and '_' only, so that "a:b" port references stay unambiguous.
std::string field(const char* prefix, const std::string& port) {
  std::string out = prefix;
  for (char c : port) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

}  // namespace

void print_nodes_text(std::ostream& os, const graph::Registry& registry) {
  const std::vector<std::string> names = registry.node_type_names();
  bool first = true;
  for (const std::string& name : names) {
    const graph::NodeType* type = registry.find_node(name);
    if (type == nullptr) continue;
    const graph::NodeSpec& spec = type->spec;
    if (!first) os << '\n';
    first = false;
    os << spec.type << "  (version " << spec.version << ", " << registry.node_origin(name)
       << (spec.has_side_effects() ? ", side effects" : "") << ")\n";
    if (!spec.doc.empty()) write_wrapped(os, spec.doc, "  ");
    print_ports(os, "inputs", spec.inputs, true);
    print_ports(os, "outputs", spec.outputs, false);
    if (!spec.params.empty()) {
      os << "  params:\n";
      for (const ParamSpec& p : spec.params) {
        os << "    " << p.name << ": " << graph::to_string(p.type);
        if (p.required) {
          os << ", required";
        } else {
          os << " = " << graph::to_string(p.default_value);
        }
        if (const std::string range = range_text(p); !range.empty()) os << ", in " << range;
        if (!p.choices.empty()) {
          os << ", one of";
          for (std::size_t i = 0; i < p.choices.size(); ++i) os << (i ? " | " : " ") << p.choices[i];
        }
        os << '\n';
        if (!p.doc.empty()) write_wrapped(os, p.doc, "        ");
      }
    }
  }
  if (names.empty()) os << "(no node types registered)\n";
}

void print_nodes_json(std::ostream& os, const graph::Registry& registry,
                      const std::vector<graph::LoadedPlugin>& plugins) {
  JsonWriter w(os);
  w.begin_object();
  w.field("kinegraph", KG_VERSION);
  w.field("plugin_abi", static_cast<std::int64_t>(graph::kPluginAbiVersion));
  w.key("plugins");
  w.begin_array();
  for (const graph::LoadedPlugin& plugin : plugins) {
    w.begin_object();
    w.field("id", plugin.id);
    w.field("version", plugin.version);
    w.field("path", plugin.path.string());
    w.field("nodes", plugin.node_count);
    w.field("extensions", plugin.extension_count);
    w.end_object();
  }
  w.end_array();
  w.key("nodes");
  w.begin_array();
  for (const std::string& name : registry.node_type_names()) {
    const graph::NodeType* type = registry.find_node(name);
    if (type == nullptr) continue;
    const graph::NodeSpec& spec = type->spec;
    w.begin_object();
    w.field("type", spec.type);
    w.field("version", spec.version);
    w.field("doc", spec.doc);
    w.field("origin", registry.node_origin(name));
    w.field("side_effects", spec.has_side_effects());
    json_ports(w, "inputs", spec.inputs, true);
    json_ports(w, "outputs", spec.outputs, false);
    w.key("params");
    w.begin_array();
    for (const ParamSpec& p : spec.params) {
      w.begin_object();
      w.field("name", p.name);
      w.field("type", graph::to_string(p.type));
      w.field("required", p.required);
      w.key("default");
      if (p.required) {
        w.null();
      } else {
        w.value(p.default_value);
      }
      w.field("min", p.min);
      w.field("max", p.max);
      w.key("choices");
      w.begin_array();
      for (const std::string& c : p.choices) w.value(c);
      w.end_array();
      w.field("doc", p.doc);
      w.end_object();
    }
    w.end_array();
    w.end_object();
  }
  w.end_array();
  w.end_object();  // ends the line too
}

void write_dot(std::ostream& os, const graph::Graph& graph, const graph::Registry& registry) {
  os << "digraph " << quoted(graph.file.filename().string()) << " {\n";
  os << "  rankdir=LR;\n";
  os << "  label=" << quoted(graph.file.filename().string()) << "; labelloc=t;\n";
  os << "  node [shape=record, fontname=\"Helvetica\", fontsize=11];\n";
  os << "  edge [fontname=\"Helvetica\", fontsize=9];\n";
  for (const graph::NodeInstance& node : graph.nodes) {
    const graph::NodeType* type = registry.find_node(node.type);
    std::string label = "{";
    if (type != nullptr && !type->spec.inputs.empty()) {
      label += "{";
      for (std::size_t i = 0; i < type->spec.inputs.size(); ++i) {
        const PortSpec& port = type->spec.inputs[i];
        label += (i ? "|<" : "<") + field("i_", port.name) + "> " + record_escape(port.name) +
                 (port.required ? "" : "?");
      }
      label += "}|";
    }
    label += record_escape(node.id) + "\\n" + record_escape(node.type);
    if (type != nullptr && !type->spec.outputs.empty()) {
      label += "|{";
      for (std::size_t i = 0; i < type->spec.outputs.size(); ++i) {
        const PortSpec& port = type->spec.outputs[i];
        label += (i ? "|<" : "<") + field("o_", port.name) + "> " + record_escape(port.name);
      }
      label += "}";
    }
    label += "}";
    os << "  " << quoted(node.id) << " [label=\"" << label << "\"];\n";
  }
  for (const graph::Connection& c : graph.connections) {
    std::string port_type;
    if (const graph::NodeInstance* from = graph.find_node(c.from.node)) {
      if (const graph::NodeType* type = registry.find_node(from->type)) {
        if (const PortSpec* port = type->spec.find_output(c.from.port)) port_type = port->type;
      }
    }
    os << "  " << quoted(c.from.node) << ':' << quoted(field("o_", c.from.port)) << ":e -> "
       << quoted(c.to.node) << ':' << quoted(field("i_", c.to.port)) << ":w [label=" << quoted(port_type)
       << ", tooltip=" << quoted(c.from.to_string() + " -> " + c.to.to_string()) << "];\n";
  }
  os << "}\n";
}

}  // namespace kg::app
