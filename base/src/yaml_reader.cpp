#include "kg/base/yaml_reader.hpp"
#include "kg/base/text.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace kg {

namespace {

std::string shown(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

SourceLocation YamlReader::at(const YAML::Node& node) const {
  const YAML::Mark m = node.Mark();
  if (m.line < 0) return {path_, 0, 0};
  return {path_, m.line + 1, m.column + 1};
}

void YamlReader::fail(const std::string& message, const YAML::Node& where) const {
  throw Error(message, at(where));
}

void YamlReader::fail(const std::string& message, const YAML::Mark& m) const {
  throw Error(message,
              m.line < 0 ? SourceLocation{path_, 0, 0} : SourceLocation{path_, m.line + 1, m.column + 1});
}

YAML::Node YamlReader::load(std::string_view text, const std::string& empty_message) const {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    const YAML::Mark m = e.mark;
    throw Error("malformed YAML: " + e.msg,
                m.line < 0 ? SourceLocation{path_} : SourceLocation{path_, m.line + 1, m.column + 1});
  }
  if (!root.IsDefined() || root.IsNull()) throw Error(empty_message, {path_, 1, 1});
  return root;
}

std::vector<YamlReader::Entry> YamlReader::entries(const YAML::Node& map, const std::string& what) const {
  if (!map.IsMap()) fail(what + " must be a map", map);
  std::vector<Entry> out;
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (!it->first.IsScalar()) fail("a key of " + what + " must be a plain text", it->first);
    Entry e{it->first.Scalar(), it->first, it->second};
    for (const Entry& prior : out)
      if (prior.key == e.key)
        fail("duplicate key " + text::in_quotes(e.key) + " in " + what + " (first at " +
                 at(prior.key_node).to_string() + ")",
             e.key_node);
    out.push_back(std::move(e));
  }
  return out;
}

void YamlReader::check_keys(const std::vector<Entry>& es, const std::string& what,
                            const std::vector<std::string>& allowed) const {
  for (const Entry& e : es) {
    if (std::find(allowed.begin(), allowed.end(), e.key) != allowed.end()) continue;
    const std::string near = nearest_name(e.key, allowed);
    fail("unknown key " + text::in_quotes(e.key) + " in " + what +
             (near.empty() ? "" : " (did you mean " + text::in_quotes(near) + "?)") +
             "; allowed: " + text::join(allowed),
         e.key_node);
  }
}

void YamlReader::check_keys(const YAML::Node& map, const std::string& path,
                            const std::vector<std::string>& allowed) const {
  for (auto it = map.begin(); it != map.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    const std::string near = nearest_name(key, allowed);
    fail("unknown key " + text::in_quotes(path.empty() ? key : path + "." + key) +
             (near.empty() ? "" : " (did you mean " + text::in_quotes(near) + "?)") +
             "; allowed: " + text::join(allowed),
         it->first.Mark());
  }
}

const YamlReader::Entry* YamlReader::find(const std::vector<Entry>& es, const std::string& key) {
  for (const Entry& e : es)
    if (e.key == key) return &e;
  return nullptr;
}

void YamlReader::check_version(const std::vector<Entry>& top) const {
  const Entry* version = find(top, "version");
  if (version == nullptr) throw Error("missing 'version: 1'", {path_, 1, 1});
  if (!version->value.IsScalar() || version->value.Scalar() != "1")
    fail("unsupported version " + text::in_quotes(version->value.IsScalar() ? version->value.Scalar() : "?") +
             " (expected 1)",
         version->value);
}

double YamlReader::number(const YAML::Node& n, const std::string& what, bool allow_infinite) const {
  if (!n.IsScalar()) fail(what + ": expected a number", n);
  const std::string& text = n.Scalar();
  std::string t = text;
  std::transform(t.begin(), t.end(), t.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const bool plus = t == ".inf" || t == "+.inf" || t == "inf" || t == "+inf";
  const bool minus = t == "-.inf" || t == "-inf";
  if ((plus || minus) && !allow_infinite)
    fail(what + ": infinity is not allowed here (expected a finite number), got " + text::in_quotes(text), n);
  if (plus) return std::numeric_limits<double>::infinity();
  if (minus) return -std::numeric_limits<double>::infinity();
  double v = 0;
  std::istringstream in(text);
  in >> v;
  if (in.fail() || !(in >> std::ws).eof())
    fail(what + ": expected a number, got " + text::in_quotes(text), n);
  if (!std::isfinite(v)) fail(what + ": expected a finite number, got " + text::in_quotes(text), n);
  return v;
}

double YamlReader::positive(const YAML::Node& n, const std::string& what) const {
  const double v = number(n, what);
  if (!(v > 0)) fail(what + ": expected a number > 0, got " + shown(v), n);
  return v;
}

double YamlReader::non_negative(const YAML::Node& n, const std::string& what) const {
  const double v = number(n, what);
  if (v < 0) fail(what + ": expected a number >= 0, got " + shown(v), n);
  return v;
}

int YamlReader::integer(const YAML::Node& n, const std::string& what) const {
  if (!n.IsScalar()) fail(what + ": expected an integer", n);
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    fail(what + ": expected an integer, got " + text::in_quotes(n.Scalar()), n);
  }
}

std::string YamlReader::text(const YAML::Node& n, const std::string& what) const {
  if (!n.IsScalar()) fail(what + ": expected a string", n);
  return n.Scalar();
}

Pattern YamlReader::pattern(const YAML::Node& n, const std::string& what) const {
  if (!n.IsScalar()) fail(what + ": expected a regular expression (a string)", n);
  try {
    return Pattern::compile(n.Scalar());
  } catch (const std::invalid_argument& e) {
    fail(what + ": " + e.what(), n);
  }
}

}  // namespace kg
