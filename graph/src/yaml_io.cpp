// Graph files: YAML -> a validated Graph. Every check happens here, before anything runs, and
// every Error carries the file:line:column of the YAML node it is about (yaml-cpp's marks are
// 0-based; ours are 1-based).
#include "kg/graph/yaml_io.hpp"

#include "kg/base/atomic_file.hpp"
#include "kg/base/yaml_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>

#include "kg/base/text.hpp"

namespace kg::graph {

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kTopKeys = {"version", "doc", "variables", "plugins", "nodes", "connections"};
const std::vector<std::string> kVariableKeys = {"doc", "default", "required"};
const std::vector<std::string> kNodeKeys = {"type", "params", "doc"};
const std::vector<std::string> kConnectionKeys = {"from", "to"};

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  const std::string near = nearest_name(name, candidates);
  return near.empty() ? std::string() : "; did you mean " + text::in_quotes(near) + "?";
}

bool is_identifier(const std::string& s, bool allow_dash) {
  if (s.empty()) return false;
  if (std::isdigit(static_cast<unsigned char>(s[0])) && !allow_dash) return false;
  return std::all_of(s.begin(), s.end(), [&](unsigned char c) {
    return std::isalnum(c) || c == '_' || (allow_dash && c == '-');
  });
}

const char* kind_of(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return "a scalar";
    default:
      return "nothing";
  }
}

// One key: value of a YAML map, with where both are.
struct Entry {
  std::string key;
  YAML::Node key_node;
  YAML::Node value;
};

class Loader {
 public:
  // With `problems`, attempt() records each Error and goes on (validate reports every problem).
  explicit Loader(std::string file, std::vector<Error>* problems = nullptr)
      : file_(std::move(file)), problems_(problems) {}

  const std::string& file() const { return file_; }

  SourceLocation at(const YAML::Mark& m) const {
    if (m.line < 0) return {file_, 0, 0};
    return {file_, m.line + 1, m.column + 1};
  }
  SourceLocation at(const YAML::Node& n) const { return at(n.Mark()); }
  // Where a value is, or its key when the value is empty (yaml-cpp puts an empty value's mark
  // wherever the next token starts, often on a later line).
  SourceLocation at(const Entry& e) const { return e.value.IsNull() ? at(e.key_node) : at(e.value); }

  [[noreturn]] void fail(const std::string& message, const SourceLocation& where) const {
    throw Error(message, where);
  }

  // Runs `step`. Collecting, an Error it throws is recorded and false returned, so the caller
  // goes on with the next item; otherwise the Error leaves.
  template <class Step>
  bool attempt(Step&& step) const {
    if (!problems_) {
      step();
      return true;
    }
    try {
      step();
      return true;
    } catch (const Error& e) {
      problems_->push_back(e);
      return false;
    }
  }
  bool collecting() const { return problems_ != nullptr; }

  YAML::Node parse(const std::string& text) const {
    const YAML::Node root = parse_yaml(text, file_);
    if (!root.IsDefined() || root.IsNull())
      fail("empty graph file (expected at least 'version: 1' and 'nodes:')", {file_, 1, 1});
    if (!root.IsMap())
      fail(std::string("a graph file must be a map of keys (version, nodes, ...), got ") + kind_of(root),
           at(root));
    return root;
  }

  // The entries of `map` (a map or null) in file order (parse_yaml has refused duplicate keys).
  std::vector<Entry> entries(const YAML::Node& map, const std::string& path) const {
    std::vector<Entry> out;
    if (map.IsNull()) return out;
    if (!map.IsMap()) fail(text::in_quotes(path) + " must be a map, got " + kind_of(map), at(map));
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (!it->first.IsScalar())
        fail("a key of " + text::in_quotes(path) + " must be a plain name", at(it->first));
      out.push_back({it->first.Scalar(), it->first, it->second});
    }
    return out;
  }

  void check_keys(const std::vector<Entry>& es, const std::string& path,
                  const std::vector<std::string>& allowed) const {
    for (const Entry& e : es) {
      if (std::find(allowed.begin(), allowed.end(), e.key) != allowed.end()) continue;
      const std::string dotted = text::key_path(path, e.key);
      fail("unknown key " + text::in_quotes(dotted) + did_you_mean(e.key, allowed) +
               " (allowed here: " + text::join(allowed) + ")",
           at(e.key_node));
    }
  }

  static const Entry* find(const std::vector<Entry>& es, const std::string& key) {
    for (const Entry& e : es)
      if (e.key == key) return &e;
    return nullptr;
  }

  // A scalar's text; `what` names the item in the message.
  std::string scalar(const Entry& e, const std::string& what, bool null_is_empty = true) const {
    if (e.value.IsNull() && null_is_empty) return {};
    if (!e.value.IsScalar()) fail(what + " must be a single value, got " + kind_of(e.value), at(e));
    return e.value.Scalar();
  }

 private:
  std::string file_;
  std::vector<Error>* problems_;
};

// ---- variables -----------------------------------------------------------------------------

class Variables {
 public:
  // With `missing`, a required variable without a value is recorded there and stands for an
  // unknown value (validate of a graph given no --set); otherwise it is an Error.
  explicit Variables(const Loader& loader, std::vector<Variable>* missing = nullptr)
      : loader_(loader), missing_(missing) {}

  // Whether `text`, substituted, holds the value of a missing required variable.
  static bool is_unknown(const std::string& text) { return text.find(kUnknownMark) != std::string::npos; }

  void declare(Variable v) { declared_.push_back(std::move(v)); }

  const std::vector<Variable>& declared() const { return declared_; }
  const std::map<std::string, std::string>& values() const { return values_; }

  const Variable* find(const std::string& name) const {
    for (const Variable& v : declared_)
      if (v.name == name) return &v;
    return nullptr;
  }

  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const Variable& v : declared_) n.push_back(v.name);
    return n;
  }

  // --set values are taken verbatim; defaults may refer to other variables.
  void resolve(const std::map<std::string, std::string>& overrides) {
    for (const auto& [name, value] : overrides) {
      if (find(name)) continue;
      std::string message = "--set " + name + "=" + value + ": the graph declares no variable " +
                            text::in_quotes(name) + did_you_mean(name, names());
      message += declared_.empty() ? " (it declares none)" : " (declared: " + text::join(names()) + ")";
      loader_.fail(message, {loader_.file(), 0, 0});
    }
    overrides_ = &overrides;
    for (const Variable& v : declared_) value_of(v.name, v.where);
    overrides_ = nullptr;
  }

  // Replaces ${name} by the variable's value and $$ by $. `where` locates `text` for messages.
  std::string substitute(const std::string& text, const SourceLocation& where) const {
    return substitute_with(text, where,
                           [&](const std::string& name, const SourceLocation& at) -> const std::string& {
                             auto it = values_.find(name);
                             if (it != values_.end()) return it->second;
                             undefined(name, at);
                           });
  }

 private:
  using Lookup = std::function<const std::string&(const std::string&, const SourceLocation&)>;

  [[noreturn]] void undefined(const std::string& name, const SourceLocation& at) const {
    std::string message = "undefined variable " + text::in_quotes(name) + did_you_mean(name, names());
    message += declared_.empty() ? " (the graph declares no variables: add it under 'variables:')"
                                 : " (declared: " + text::join(names()) + ")";
    loader_.fail(message, at);
  }

  std::string substitute_with(const std::string& text, const SourceLocation& where,
                              const Lookup& lookup) const {
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (c != '$' || i + 1 >= text.size()) {
        out += c;
        continue;
      }
      if (text[i + 1] == '$') {
        out += '$';
        ++i;
        continue;
      }
      if (text[i + 1] != '{') {
        out += c;
        continue;
      }
      const std::size_t close = text.find('}', i + 2);
      if (close == std::string::npos)
        loader_.fail("unterminated '${' in " + text::excerpt(text) + " (write $$ for a literal dollar)",
                     where);
      const std::string name = text.substr(i + 2, close - i - 2);
      if (!is_identifier(name, false))
        loader_.fail("bad variable reference " + text::excerpt("${" + name + "}") + " in " +
                         text::excerpt(text) +
                         ": a name has letters, digits and '_' (write $$ for a literal dollar)",
                     where);
      const std::string& value = lookup(name, where);
      if (out.size() + value.size() > kMaxExpandedBytes)
        loader_.fail("expanding " + text::excerpt(text) + " gives over " + std::to_string(kMaxExpandedBytes) +
                         " bytes (the limit of a text after " + "${...} expansion) at ${" + name + "} (" +
                         std::to_string(value.size()) + " bytes)",
                     where);
      out += value;
      i = close;
    }
    return out;
  }

  const std::string& value_of(const std::string& name, const SourceLocation& used_at) {
    if (auto it = values_.find(name); it != values_.end()) return it->second;
    const Variable* v = find(name);
    if (!v) undefined(name, used_at);
    if (auto it = overrides_->find(name); it != overrides_->end()) return values_[name] = it->second;
    if (v->required && missing_) {
      missing_->push_back(*v);
      return values_[name] = kUnknownMark + name + kUnknownMark;
    }
    if (v->required)
      loader_.fail("variable " + text::in_quotes(name) + " is required and has no value: pass --set " + name +
                       "=value" + (v->doc.empty() ? std::string() : " (" + v->doc + ")"),
                   v->where);
    if (std::find(resolving_.begin(), resolving_.end(), name) != resolving_.end()) {
      std::vector<std::string> chain(std::find(resolving_.begin(), resolving_.end(), name), resolving_.end());
      chain.push_back(name);
      loader_.fail("variable defaults refer to each other in a cycle: " + text::join(chain, " -> "),
                   v->where);
    }
    resolving_.push_back(name);
    std::string value =
        substitute_with(v->default_value, v->where,
                        [&](const std::string& n, const SourceLocation& at) -> const std::string& {
                          return value_of(n, at);
                        });
    resolving_.pop_back();
    return values_[name] = std::move(value);
  }

  static constexpr char kUnknownMark = '\x01';

  const Loader& loader_;
  std::vector<Variable>* missing_;
  std::vector<Variable> declared_;
  std::map<std::string, std::string> values_;
  const std::map<std::string, std::string>* overrides_ = nullptr;
  std::vector<std::string> resolving_;
};

// ---- the parts every reader needs: version, variables, plugins ----------------------------------

struct Head {
  YAML::Node root;
  std::vector<Entry> top;
  std::string doc;
  std::vector<PluginEntry> plugins;
};

std::optional<bool> parse_bool(std::string text) {
  text = std::string(text::trim(text));
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (text == "true" || text == "yes" || text == "1" || text == "on") return true;
  if (text == "false" || text == "no" || text == "0" || text == "off") return false;
  return std::nullopt;
}

// Version, doc and the variables declared, none resolved yet. `root` is L.parse's document.
Head read_declarations(const Loader& L, Variables& vars, const YAML::Node& root) {
  Head h;
  h.root = root;
  h.top = L.entries(h.root, "");

  // The version first: a file of another version may well have other keys.
  const Entry* version = Loader::find(h.top, "version");
  if (!version)
    L.fail("missing 'version: " + std::to_string(kGraphFormatVersion) +
               "' (this kinegraph reads graph format version " + std::to_string(kGraphFormatVersion) + ")",
           L.at(h.root));
  const std::string vtext =
      version->value.IsScalar() ? version->value.Scalar() : std::string(kind_of(version->value));
  const auto v = text::parse_int(vtext);
  if (!version->value.IsScalar() || !v || *v != kGraphFormatVersion)
    L.fail("unsupported graph format version " + text::in_quotes(vtext) + "; this kinegraph reads version " +
               std::to_string(kGraphFormatVersion),
           L.at(*version));
  L.check_keys(h.top, "", kTopKeys);

  if (const Entry* doc = Loader::find(h.top, "doc")) h.doc = L.scalar(*doc, "'doc'");

  if (const Entry* vs = Loader::find(h.top, "variables")) {
    for (const Entry& e : L.entries(vs->value, "variables")) {
      const std::string path = text::key_path("variables", e.key);
      if (!is_identifier(e.key, false))
        L.fail("variable name " + text::in_quotes(e.key) +
                   " must be letters, digits and '_', not starting with a digit",
               L.at(e.key_node));
      if (!e.value.IsMap() && !e.value.IsNull())
        L.fail(
            text::in_quotes(path) +
                " must be a map like {doc: \"...\", default: value} or {doc: \"...\", required: true}, got " +
                kind_of(e.value),
            L.at(e));
      const auto fields = L.entries(e.value, path);
      L.check_keys(fields, path, kVariableKeys);
      Variable var;
      var.name = e.key;
      var.where = L.at(e.key_node);
      if (const Entry* d = Loader::find(fields, "doc"))
        var.doc = L.scalar(*d, text::in_quotes(path + ".doc"));
      if (const Entry* r = Loader::find(fields, "required")) {
        const std::string t = L.scalar(*r, text::in_quotes(path + ".required"), false);
        const auto b = parse_bool(t);
        if (!b)
          L.fail(text::in_quotes(path + ".required") + " must be true or false, got " + text::in_quotes(t),
                 L.at(*r));
        var.required = *b;
      }
      if (const Entry* d = Loader::find(fields, "default")) {
        if (var.required)
          L.fail("variable " + text::in_quotes(e.key) +
                     " is required, so it takes no default (drop one of them)",
                 L.at(d->key_node));
        if (!d->value.IsNull() && !d->value.IsScalar())
          L.fail(text::in_quotes(path + ".default") +
                     " must be a single value (write a list as a string: \"1, 2, 3\"), got " +
                     kind_of(d->value),
                 L.at(*d));
        var.default_value = L.scalar(*d, text::in_quotes(path + ".default"));
      }
      vars.declare(std::move(var));
    }
  }
  return h;
}

Head read_head(const Loader& L, Variables& vars, const YAML::Node& root,
               const std::map<std::string, std::string>& overrides) {
  Head h = read_declarations(L, vars, root);
  vars.resolve(overrides);

  if (const Entry* ps = Loader::find(h.top, "plugins")) {
    if (!ps->value.IsNull() && !ps->value.IsSequence())
      L.fail("'plugins' must be a list of plugin names or paths, got " + std::string(kind_of(ps->value)),
             L.at(*ps));
    std::size_t index = 0;
    for (const YAML::Node& item : ps->value) {
      const std::string path = "plugins[" + std::to_string(index++) + "]";
      if (!item.IsScalar())
        L.fail(text::in_quotes(path) + " must be a plugin name or path, got " + kind_of(item), L.at(item));
      std::string entry = vars.substitute(item.Scalar(), L.at(item));
      // An entry that is empty after substitution is an optional plugin left out; one naming a
      // missing variable's value cannot be loaded.
      if (!text::trim(entry).empty() && !Variables::is_unknown(entry))
        h.plugins.push_back({std::move(entry), L.at(item)});
    }
  }
  return h;
}

// ---- params -----------------------------------------------------------------------------------

class ParamReader {
 public:
  ParamReader(const Loader& L, const Variables& vars, const std::string& node_id, const NodeSpec& spec)
      : L_(L), vars_(vars), node_id_(node_id), spec_(spec) {}

  ParamValue read(const ParamSpec& p, const Entry& e) const {
    const std::string who = "param " + text::in_quotes(p.name) + " of node " + text::in_quotes(node_id_) +
                            " (" + spec_.type + ")";
    const SourceLocation where = L_.at(e);
    if (e.value.IsNull()) L_.fail(who + " has no value (expected " + expected(p) + ")", where);
    if (e.value.IsMap()) L_.fail(who + " expects " + expected(p) + ", got a map", where);

    if (p.type == ParamType::FloatList) {
      std::vector<double> list;
      if (e.value.IsSequence()) {
        std::size_t i = 0;
        for (const YAML::Node& item : e.value) {
          const SourceLocation at = L_.at(item);
          if (!item.IsScalar())
            L_.fail(who + ": element " + std::to_string(i) + " must be a number, got " + kind_of(item), at);
          const std::string text = vars_.substitute(item.Scalar(), at);
          const auto x = text::parse_double(text);
          if (!x)
            L_.fail(who + ": element " + std::to_string(i) + " is " + shown(text, item.Scalar()) +
                        ", not a number",
                    at);
          list.push_back(*x);
          ++i;
        }
      } else {
        const std::string raw = e.value.Scalar();
        const std::string text = vars_.substitute(raw, where);
        list = parse_list(who, text, raw, where);
      }
      for (std::size_t i = 0; i < list.size(); ++i)
        check_range(p, list[i], who + (list.size() > 1 ? " element " + std::to_string(i) : std::string()),
                    where);
      return list;
    }

    if (e.value.IsSequence()) L_.fail(who + " expects " + expected(p) + ", got a list", where);
    const std::string raw = e.value.Scalar();
    const std::string text = vars_.substitute(raw, where);
    switch (p.type) {
      case ParamType::Bool: {
        const auto b = parse_bool(text);
        if (!b) L_.fail(who + " expects a bool (true/false, yes/no, 1/0), got " + shown(text, raw), where);
        return *b;
      }
      case ParamType::Int: {
        const auto i = text::parse_int(text);
        if (!i) L_.fail(who + " expects an int, got " + shown(text, raw), where);
        check_range(p, static_cast<double>(*i), who, where);
        return *i;
      }
      case ParamType::Float: {
        const auto x = text::parse_double(text);
        if (!x) L_.fail(who + " expects a float, got " + shown(text, raw), where);
        check_range(p, *x, who, where);
        return *x;
      }
      case ParamType::Enum: {
        if (std::find(p.choices.begin(), p.choices.end(), text) == p.choices.end())
          L_.fail(who + " must be one of " + text::join(p.choices) + "; got " + shown(text, raw) +
                      did_you_mean(text, p.choices),
                  where);
        return text;
      }
      case ParamType::InputPath:
      case ParamType::OutputPath:
        // No file has such a name, and every message naming the file would carry it whole; a NUL
        // would end the name the system opens before the one the reader checked.
        if (text.size() >= PATH_MAX)
          L_.fail(who + " expects a path, got " + text::excerpt(text) +
                      ", longer than the system's longest (" + std::to_string(PATH_MAX - 1) + " bytes)",
                  where);
        if (text.find('\0') != std::string::npos)
          L_.fail(who + " expects a path, got " + shown(text, raw) + ", which holds a NUL byte", where);
        return text;
      default:
        return text;  // String
    }
  }

  static std::string expected(const ParamSpec& p) {
    switch (p.type) {
      case ParamType::Bool:
        return "a bool";
      case ParamType::Int:
        return "an int";
      case ParamType::Float:
        return "a float";
      case ParamType::Enum:
        return "one of " + text::join(p.choices);
      case ParamType::FloatList:
        return "a list of numbers";
      case ParamType::InputPath:
      case ParamType::OutputPath:
        return "a path";
      default:
        return "a string";
    }
  }

 private:
  // The text after substitution, and what it was written as when a variable supplied it.
  static std::string shown(const std::string& text, const std::string& raw) {
    return text == raw ? text::in_quotes(text)
                       : text::in_quotes(text) + " (from " + text::in_quotes(raw) + ")";
  }

  // "0,-9.81,0", "[0, -9.81, 0]", "0 -9.81 0" or one number, typically from a variable.
  std::vector<double> parse_list(const std::string& who, const std::string& text, const std::string& raw,
                                 const SourceLocation& where) const {
    std::string_view body = text::trim(text);
    if (!body.empty() && body.front() == '[') {
      if (body.back() != ']')
        L_.fail(who + " expects a list of numbers, got " + shown(text, raw) + " (no closing ']')", where);
      body = text::trim(body.substr(1, body.size() - 2));
    }
    std::vector<double> list;
    std::vector<std::string> items;
    if (body.find(',') != std::string_view::npos) {
      std::size_t from = 0;
      while (true) {
        const std::size_t comma = body.find(',', from);
        const std::string_view item =
            text::trim(body.substr(from, comma == std::string_view::npos ? body.npos : comma - from));
        if (item.empty())
          L_.fail(who + " expects a list of numbers, got " + shown(text, raw) + " (an empty element)", where);
        items.emplace_back(item);
        if (comma == std::string_view::npos) break;
        from = comma + 1;
      }
    } else {
      std::istringstream words{std::string(body)};
      for (std::string w; words >> w;) items.push_back(w);
    }
    for (std::size_t i = 0; i < items.size(); ++i) {
      const auto x = text::parse_double(items[i]);
      if (!x)
        L_.fail(who + " expects a list of numbers; element " + std::to_string(i) + " " +
                    text::in_quotes(items[i]) + " of " + shown(text, raw) + " is not a number",
                where);
      list.push_back(*x);
    }
    return list;
  }

  void check_range(const ParamSpec& p, double x, const std::string& who, const SourceLocation& where) const {
    auto show = [&](double v) {
      return p.type == ParamType::Int ? std::to_string(static_cast<std::int64_t>(v)) : text::format_double(v);
    };
    if (p.min && x < *p.min)
      L_.fail(who + " is " + show(x) + ", below its minimum " + show(*p.min) + range_text(p, show), where);
    if (p.max && x > *p.max)
      L_.fail(who + " is " + show(x) + ", above its maximum " + show(*p.max) + range_text(p, show), where);
  }

  template <class Show>
  static std::string range_text(const ParamSpec& p, Show show) {
    if (p.min && p.max) return " (allowed: " + show(*p.min) + " to " + show(*p.max) + ")";
    return {};
  }

  const Loader& L_;
  const Variables& vars_;
  const std::string& node_id_;
  const NodeSpec& spec_;
};

// ---- connections and the whole graph ---------------------------------------------------------

std::string port_list(const std::vector<PortSpec>& ports) {
  std::vector<std::string> names;
  for (const PortSpec& p : ports) names.push_back(p.name + " (" + p.type + ")");
  return names.empty() ? std::string("none") : text::join(names);
}

std::vector<std::string> port_names(const std::vector<PortSpec>& ports) {
  std::vector<std::string> names;
  for (const PortSpec& p : ports) names.push_back(p.name);
  return names;
}

// Where each given param's value is, for messages about it after parsing.
using ParamPlaces = std::map<std::pair<std::size_t, std::string>, SourceLocation>;

std::string canonical_text(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) return fs::absolute(path).lexically_normal().string();
  return p.string();
}

// Outputs that would overwrite an input or each other; collecting (validate), also inputs that do
// not exist and that no node of the graph writes.
void check_paths(const Loader& L, const Graph& g, const Registry& registry, const ParamPlaces& places) {
  struct PathUse {
    std::size_t node;
    std::string param;
    std::string text;
    std::string canonical;
  };
  std::vector<PathUse> inputs, outputs;
  for (std::size_t i = 0; i < g.nodes.size(); ++i) {
    const NodeSpec& spec = registry.find_node(g.nodes[i].type)->spec;
    for (const ParamSpec& p : spec.params) {
      if (p.type != ParamType::InputPath && p.type != ParamType::OutputPath) continue;
      if (!g.nodes[i].params.has(p.name)) continue;
      const std::string& text = g.nodes[i].params.get<std::string>(p.name);
      if (text::trim(text).empty() || Variables::is_unknown(text)) continue;
      (p.type == ParamType::InputPath ? inputs : outputs).push_back({i, p.name, text, canonical_text(text)});
    }
  }
  auto place = [&](const PathUse& u) {
    auto it = places.find({u.node, u.param});
    return it != places.end() ? it->second : g.nodes[u.node].where;
  };
  auto name = [&](const PathUse& u) {
    return "param '" + u.param + "' of node '" + g.nodes[u.node].id + "'";
  };
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    for (const PathUse& in : inputs)
      if (outputs[o].canonical == in.canonical)
        L.attempt([&] {
          L.fail(name(outputs[o]) + " would overwrite input " + text::in_quotes(in.text) + " (read by " +
                     name(in) + " at " + place(in).to_string() + "): " + text::in_quotes(outputs[o].text) +
                     " is the same file",
                 place(outputs[o]));
        });
    for (std::size_t p = 0; p < o; ++p)
      if (outputs[o].canonical == outputs[p].canonical)
        L.attempt([&] {
          L.fail(name(outputs[o]) + " writes " + text::in_quotes(outputs[o].text) + ", which " +
                     name(outputs[p]) + " (" + place(outputs[p]).to_string() + ") writes too",
                 place(outputs[o]));
        });
  }
  // A run reports a missing input when the node reading it runs, after the solves before it.
  if (!L.collecting()) return;
  for (const PathUse& in : inputs) {
    std::error_code ec;
    if (fs::exists(in.text, ec)) continue;
    const bool written_here = std::any_of(outputs.begin(), outputs.end(),
                                          [&](const PathUse& out) { return out.canonical == in.canonical; });
    if (written_here) continue;
    L.attempt([&] {
      L.fail(name(in) + " reads " + text::in_quotes(in.text) + ", which does not exist" +
                 (ec ? " (" + ec.message() + ")" : std::string()),
             place(in));
    });
  }
}

// A cycle as node indices (first == last), or empty.
std::vector<std::size_t> find_cycle(std::size_t n, const std::vector<Connection>& connections,
                                    const std::map<std::string, std::size_t>& index) {
  std::vector<std::vector<std::size_t>> next(n);
  for (const Connection& c : connections) next[index.at(c.from.node)].push_back(index.at(c.to.node));
  enum : char { White, Grey, Black };
  std::vector<char> colour(n, White);
  std::vector<std::size_t> stack;
  std::vector<std::size_t> cycle;
  std::function<bool(std::size_t)> visit = [&](std::size_t u) {
    colour[u] = Grey;
    stack.push_back(u);
    for (std::size_t v : next[u]) {
      if (colour[v] == Grey) {
        cycle.assign(std::find(stack.begin(), stack.end(), v), stack.end());
        cycle.push_back(v);
        return true;
      }
      if (colour[v] == White && visit(v)) return true;
    }
    stack.pop_back();
    colour[u] = Black;
    return false;
  };
  for (std::size_t u = 0; u < n; ++u)
    if (colour[u] == White && visit(u)) break;
  return cycle;
}

// The node's id, map and type checked; nullptr (and the problem recorded) when its type is unknown.
const NodeType* read_node_type(const Loader& L, const Registry& registry, const Entry& e,
                               std::vector<Entry>& fields) {
  const std::string path = text::key_path("nodes", e.key);
  const SourceLocation where = L.at(e.key_node);
  if (!is_identifier(e.key, true))
    L.fail("node id " + text::in_quotes(e.key) + " may hold only letters, digits, '_' and '-'", where);
  if (!e.value.IsMap())
    L.fail(text::in_quotes(path) + " must be a map like {type: stage.name, params: {...}}, got " +
               kind_of(e.value),
           L.at(e));
  fields = L.entries(e.value, path);
  L.attempt([&] { L.check_keys(fields, path, kNodeKeys); });
  if (const Entry* doc = Loader::find(fields, "doc"))
    L.attempt([&] { L.scalar(*doc, text::in_quotes(path + ".doc")); });
  const Entry* type_entry = Loader::find(fields, "type");
  if (!type_entry) L.fail("node " + text::in_quotes(e.key) + " has no 'type'", where);
  const std::string type = L.scalar(*type_entry, text::in_quotes(path + ".type"));
  if (type.empty()) L.fail("node " + text::in_quotes(e.key) + " has an empty 'type'", L.at(*type_entry));
  const NodeType* node_type = registry.find_node(type);
  if (!node_type) {
    const auto names = registry.node_type_names();
    std::string message =
        "unknown node type " + text::in_quotes(type) + " for node " + text::in_quotes(e.key);
    const std::string near = nearest_name(type, names);
    if (!near.empty())
      message += "; did you mean " + text::in_quotes(near) + "?";
    else if (names.empty())
      message += " (no node types are registered: were the plugins loaded?)";
    else
      message += " (`kinegraph nodes` lists the " + std::to_string(names.size()) + " known types)";
    L.fail(message, L.at(*type_entry));
  }
  return node_type;
}

// Whether `value` (a param's scalar or list), substituted, holds a missing variable's value.
bool names_unknown(const Variables& vars, const Loader& L, const YAML::Node& value) {
  auto unknown = [&](const YAML::Node& n) {
    if (!n.IsScalar()) return false;
    try {
      return Variables::is_unknown(vars.substitute(n.Scalar(), L.at(n)));
    } catch (const Error&) {
      return false;  // the param's reader reports it
    }
  };
  if (value.IsSequence()) return std::any_of(value.begin(), value.end(), unknown);
  return unknown(value);
}

// Collecting (`problems` given), every problem the graph has is recorded and the graph returned
// as far as it could be read, its nodes made only when all was well; `missing` then receives the
// required variables given no value, which stand for unknown values that are not checked.
Graph build(const YAML::Node& root, const std::string& file_name, const fs::path& file,
            const Registry& registry, const std::map<std::string, std::string>& overrides,
            std::vector<Error>* problems = nullptr, std::vector<Variable>* missing = nullptr) {
  Loader L(file_name, problems);
  Variables vars(L, missing);
  Head head = read_head(L, vars, root, overrides);

  Graph g;
  g.file = file;
  g.doc = head.doc;
  g.variables = vars.declared();
  g.values = vars.values();
  for (const PluginEntry& p : head.plugins) g.plugins.push_back(p.entry);

  // Nodes, their types and params.
  const Entry* nodes = Loader::find(head.top, "nodes");
  if (!nodes || nodes->value.IsNull())
    L.fail("the graph has no nodes (add a 'nodes:' map of id: {type: ..., params: {...}})",
           nodes ? L.at(nodes->key_node) : L.at(head.root));
  std::map<std::string, std::size_t> index;
  std::set<std::string> unreadable;  // nodes whose type is not known: connections to them are not checked
  std::vector<bool> makeable;        // per node: its params all read and known
  ParamPlaces places;
  for (const Entry& e : L.entries(nodes->value, "nodes")) {
    std::vector<Entry> fields;
    const NodeType* node_type = nullptr;
    if (!L.attempt([&] { node_type = read_node_type(L, registry, e, fields); })) {
      unreadable.insert(e.key);
      continue;
    }
    const NodeSpec& spec = node_type->spec;
    const std::string path = text::key_path("nodes", e.key);

    NodeInstance node;
    node.id = e.key;
    node.type = spec.type;
    node.where = L.at(e.key_node);
    const std::size_t node_index = g.nodes.size();
    bool complete = true;
    std::set<std::string> unknown_params;
    if (const Entry* ps = Loader::find(fields, "params")) {
      ParamReader reader(L, vars, node.id, spec);
      std::vector<Entry> given;
      complete = L.attempt([&] { given = L.entries(ps->value, path + ".params"); });
      for (const Entry& pe : given) {
        complete &= L.attempt([&] {
          const ParamSpec* p = spec.find_param(pe.key);
          if (!p) {
            std::vector<std::string> names;
            for (const ParamSpec& q : spec.params) names.push_back(q.name);
            L.fail("unknown param " + text::in_quotes(pe.key) + " for node " + text::in_quotes(node.id) +
                       " (" + spec.type + ")" + did_you_mean(pe.key, names) +
                       (names.empty() ? " (it takes no params)" : " (params: " + text::join(names) + ")"),
                   L.at(pe.key_node));
          }
          if (missing && names_unknown(vars, L, pe.value)) {
            unknown_params.insert(p->name);
            return;
          }
          node.params.set(p->name, reader.read(*p, pe));
          places[{node_index, p->name}] = L.at(pe);
        });
      }
    }
    for (const ParamSpec& p : spec.params) {
      if (node.params.has(p.name) || unknown_params.count(p.name)) continue;
      if (p.required) {
        complete &= L.attempt([&] {
          L.fail("node " + text::in_quotes(node.id) + " (" + spec.type + ") needs param " +
                     text::in_quotes(p.name) + " (" + to_string(p.type) +
                     (p.doc.empty() ? std::string() : ": " + p.doc) + ")",
                 node.where);
        });
        continue;
      }
      node.params.set(p.name, p.default_value);
    }
    index[node.id] = node_index;
    makeable.push_back(complete && unknown_params.empty());
    g.nodes.push_back(std::move(node));
  }
  if (g.nodes.empty() && unreadable.empty()) L.fail("the graph has no nodes", L.at(nodes->key_node));

  auto spec_of = [&](std::size_t i) -> const NodeSpec& { return registry.find_node(g.nodes[i].type)->spec; };
  std::vector<std::string> ids;
  for (const NodeInstance& n : g.nodes) ids.push_back(n.id);
  ids.insert(ids.end(), unreadable.begin(), unreadable.end());

  // Connections. One touching an unreadable node is not checked, nor is its input's need of one.
  std::set<std::string> unsure_inputs;
  if (const Entry* cs = Loader::find(head.top, "connections")) {
    if (!cs->value.IsNull() && !cs->value.IsSequence())
      L.fail("'connections' must be a list of {from: node.port, to: node.port}, got " +
                 std::string(kind_of(cs->value)),
             L.at(*cs));
    std::size_t k = 0;
    for (const YAML::Node& item : cs->value) {
      const std::string path = "connections[" + std::to_string(k++) + "]";
      L.attempt([&] {
        const SourceLocation where = L.at(item);
        if (!item.IsMap())
          L.fail(
              text::in_quotes(path) + " must be a map {from: node.port, to: node.port}, got " + kind_of(item),
              where);
        const auto fields = L.entries(item, path);
        L.check_keys(fields, path, kConnectionKeys);
        Connection c;
        c.where = where;
        bool unchecked = false;
        for (const char* end : {"from", "to"}) {
          const Entry* f = Loader::find(fields, end);
          if (!f) L.fail(text::in_quotes(path) + " has no '" + end + "'", where);
          const std::string text = L.scalar(*f, text::in_quotes(path + "." + end), false);
          const SourceLocation at = L.at(*f);
          const std::size_t dot = text.find('.');
          if (dot == std::string::npos || dot == 0 || dot + 1 == text.size())
            L.fail(text::in_quotes(path + "." + end) + " must be 'node.port', got " + text::in_quotes(text),
                   at);
          PortRef ref{text.substr(0, dot), text.substr(dot + 1)};
          const bool is_from = std::string(end) == "from";
          if (unreadable.count(ref.node)) {
            unchecked = true;
            (is_from ? c.from : c.to) = std::move(ref);
            continue;
          }
          auto found = index.find(ref.node);
          if (found == index.end())
            L.fail("unknown node " + text::in_quotes(ref.node) + " in " + path + "." + end +
                       did_you_mean(ref.node, ids) + " (nodes: " + text::join(ids) + ")",
                   at);
          const NodeSpec& spec = spec_of(found->second);
          const auto& ports = is_from ? spec.outputs : spec.inputs;
          const auto& others = is_from ? spec.inputs : spec.outputs;
          if (!(is_from ? spec.find_output(ref.port) : spec.find_input(ref.port))) {
            if (std::any_of(others.begin(), others.end(),
                            [&](const PortSpec& p) { return p.name == ref.port; }))
              L.fail(ref.to_string() + " is an " + (is_from ? "input" : "output") + " of node " +
                         text::in_quotes(ref.node) + " (" + spec.type +
                         "); a connection goes from an output to an input",
                     at);
            L.fail("node " + text::in_quotes(ref.node) + " (" + spec.type + ") has no " +
                       (is_from ? "output " : "input ") + text::in_quotes(ref.port) +
                       did_you_mean(ref.port, port_names(ports)) + " (" +
                       (is_from ? "outputs: " : "inputs: ") + port_list(ports) + ")",
                   at);
          }
          (is_from ? c.from : c.to) = std::move(ref);
        }
        if (unchecked) {
          unsure_inputs.insert(c.to.to_string());
          return;
        }
        const PortSpec* out = spec_of(index[c.from.node]).find_output(c.from.port);
        const PortSpec* in = spec_of(index[c.to.node]).find_input(c.to.port);
        if (out->type != in->type)
          L.fail(c.to.to_string() + " expects " + in->type + ", got " + out->type + " from " +
                     c.from.to_string(),
                 where);
        for (const Connection& prior : g.connections)
          if (prior.to.node == c.to.node && prior.to.port == c.to.port)
            L.fail("input " + c.to.to_string() + " has two connections: from " + prior.from.to_string() +
                       " (" + prior.where.to_string() + ") and from " + c.from.to_string() + " (" +
                       where.to_string() + "); an input takes one",
                   where);
        g.connections.push_back(std::move(c));
      });
    }
  }

  // Every required input connected.
  for (std::size_t i = 0; i < g.nodes.size(); ++i) {
    for (const PortSpec& in : spec_of(i).inputs) {
      if (!in.required) continue;
      const bool connected = std::any_of(
          g.connections.begin(), g.connections.end(),
          [&](const Connection& c) { return c.to.node == g.nodes[i].id && c.to.port == in.name; });
      if (connected || unsure_inputs.count(g.nodes[i].id + "." + in.name)) continue;
      std::vector<std::string> candidates;
      for (std::size_t j = 0; j < g.nodes.size(); ++j)
        for (const PortSpec& out : spec_of(j).outputs)
          if (j != i && out.type == in.type) candidates.push_back(g.nodes[j].id + "." + out.name);
      L.attempt([&] {
        L.fail("required input " + g.nodes[i].id + "." + in.name + " (" + in.type + ") of node " +
                   text::in_quotes(g.nodes[i].id) + " (" + g.nodes[i].type + ") is not connected" +
                   (candidates.empty() ? std::string(" (no node of the graph outputs " + in.type + ")")
                                       : " (outputs of that type: " + text::join(candidates) + ")"),
               g.nodes[i].where);
      });
    }
  }

  // No cycle.
  const auto cycle = find_cycle(g.nodes.size(), g.connections, index);
  if (!cycle.empty()) {
    std::vector<std::string> names;
    for (std::size_t i : cycle) names.push_back(g.nodes[i].id);
    SourceLocation where = g.nodes[cycle.front()].where;
    for (const Connection& c : g.connections)
      if (c.from.node == names[names.size() - 2] && c.to.node == names.back()) where = c.where;
    L.attempt([&] { L.fail("the graph has a cycle: " + text::join(names, " -> "), where); });
  }

  check_paths(L, g, registry, places);

  // Only nodes whose params all read get made (each checks its settings together).
  for (std::size_t i = 0; i < g.nodes.size(); ++i) {
    NodeInstance& n = g.nodes[i];
    if (!makeable[i]) continue;
    L.attempt([&] {
      try {
        n.node = registry.create_node(n.type, n.params);
      } catch (const std::exception& e) {
        L.fail("node " + text::in_quotes(n.id) + " (" + n.type + "): " + e.what(), n.where);
      }
    });
  }
  return g;
}

std::string read_text(const fs::path& file) {
  return read_input_file(file, "graph file");
}

}  // namespace

struct GraphDocument::Parsed {
  std::string file_name;
  fs::path file;
  YAML::Node root;
};

GraphDocument::GraphDocument(std::shared_ptr<const Parsed> parsed) : parsed_(std::move(parsed)) {}

GraphDocument GraphDocument::from_file(const fs::path& file) {
  return GraphDocument(std::make_shared<const Parsed>(
      Parsed{file.string(), file, Loader(file.string()).parse(read_text(file))}));
}

GraphDocument GraphDocument::from_string(const std::string& text, const std::string& file_name) {
  return GraphDocument(
      std::make_shared<const Parsed>(Parsed{file_name, fs::path(file_name), Loader(file_name).parse(text)}));
}

std::vector<Variable> GraphDocument::variables() const {
  Loader L(parsed_->file_name);
  Variables vars(L);
  read_declarations(L, vars, parsed_->root);
  return vars.declared();
}

std::vector<PluginEntry> GraphDocument::plugins(const std::map<std::string, std::string>& overrides,
                                                bool allow_missing) const {
  Loader L(parsed_->file_name);
  std::vector<Variable> missing;
  Variables vars(L, allow_missing ? &missing : nullptr);
  return read_head(L, vars, parsed_->root, overrides).plugins;
}

Graph GraphDocument::load(const Registry& registry,
                          const std::map<std::string, std::string>& overrides) const {
  return build(parsed_->root, parsed_->file_name, parsed_->file, registry, overrides);
}

GraphCheck GraphDocument::check(const Registry& registry,
                                const std::map<std::string, std::string>& overrides) const {
  GraphCheck result;
  try {
    result.graph = build(parsed_->root, parsed_->file_name, parsed_->file, registry, overrides,
                         &result.problems, &result.needed);
  } catch (const Error& e) {
    result.problems.push_back(e);  // the file's head or its list of nodes: nothing after it can be read
  }
  return result;
}

std::vector<PluginEntry> read_graph_plugins(const fs::path& file,
                                            const std::map<std::string, std::string>& overrides) {
  return GraphDocument::from_file(file).plugins(overrides);
}

std::vector<Variable> read_graph_variables(const fs::path& file) {
  return GraphDocument::from_file(file).variables();
}

std::vector<Variable> read_graph_variables_from_string(const std::string& text,
                                                       const std::string& file_name) {
  return GraphDocument::from_string(text, file_name).variables();
}

Graph load_graph(const fs::path& file, const Registry& registry,
                 const std::map<std::string, std::string>& overrides) {
  return GraphDocument::from_file(file).load(registry, overrides);
}

Graph load_graph_from_string(const std::string& text, const std::string& file_name, const Registry& registry,
                             const std::map<std::string, std::string>& overrides) {
  return GraphDocument::from_string(text, file_name).load(registry, overrides);
}

}  // namespace kg::graph
