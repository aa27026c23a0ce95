#include "kg/base/yaml_reader.hpp"
#include "kg/base/text.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace kg {

namespace {

SourceLocation located(const std::string& path, const YAML::Mark& m) {
  return m.line < 0 ? SourceLocation{path} : SourceLocation{path, m.line + 1, m.column + 1};
}

// Walks each distinct node of a document once: an alias is the very node it names, found again
// by its mark (and confirmed with Node::is, since a flow map used as the first key of a block map
// starts where that map starts). Counts the document's distinct nodes and its nodes as a reader
// walking it would meet them (aliases expanded), and refuses duplicate keys.
class DocumentCheck {
 public:
  explicit DocumentCheck(const std::string& path) : path_(path) {}

  void run(const YAML::Node& root) {
    const long long expanded = walk(root);
    if (expanded > distinct_ + kMaxYamlAliasGrowth)
      throw Error("aliases expand this document from " + std::to_string(distinct_) + " to over " +
                      std::to_string(distinct_ + kMaxYamlAliasGrowth) + " nodes (at most " +
                      std::to_string(kMaxYamlAliasGrowth) + " more nodes through aliases)",
                  located(path_, root.Mark()));
  }

 private:
  static constexpr long long kCap = 1LL << 60;  // expanded counts saturate here

  long long walk(const YAML::Node& n) {
    if (!n.IsMap() && !n.IsSequence()) {
      ++distinct_;  // an aliased scalar counts again; only collections can multiply a document
      return 1;
    }
    auto& seen = seen_[n.Mark().pos];
    for (const auto& [node, count] : seen)
      if (node.is(n)) return count;
    // An alias inside the collection it names (`a: &a {b: *a}`) makes yaml-cpp build a cycle:
    // every reader walking it would recurse without end.
    for (const auto& open : open_)
      if (open.is(n))
        throw Error(
            "an alias " + where() + " names a collection that contains it (a cycle no reader can walk)",
            located(path_, n.Mark()));
    open_.push_back(n);
    ++distinct_;
    long long count = 1;
    if (n.IsMap()) {
      std::unordered_map<std::string, YAML::Mark> keys;
      std::size_t i = 0;
      for (auto it = n.begin(); it != n.end(); ++it, ++i) {
        if (it->first.IsScalar()) {
          const auto [first, inserted] = keys.emplace(it->first.Scalar(), it->first.Mark());
          if (!inserted)
            throw Error("duplicate key " + text::excerpt(it->first.Scalar()) + " " + where() + " (first at " +
                            located(path_, first->second).to_string() + ")",
                        located(path_, it->first.Mark()));
          path_keys_.push_back({it->first.Scalar(), -1});
        } else {
          path_keys_.push_back({"", static_cast<long long>(i)});
        }
        count = std::min(kCap, count + walk(it->first) + walk(it->second));
        path_keys_.pop_back();
      }
    } else {
      long long i = 0;
      for (auto it = n.begin(); it != n.end(); ++it, ++i) {
        path_keys_.push_back({"", i});
        count = std::min(kCap, count + walk(*it));
        path_keys_.pop_back();
      }
    }
    open_.pop_back();
    seen_[n.Mark().pos].push_back({n, count});
    return count;
  }

  // "at the top level", "in 'nodes.a.params'", "in 'constraints[2]'": where the walk is.
  std::string where() const {
    if (path_keys_.empty()) return "at the top level";
    std::string out;  // the dotted path, quoted below
    for (const auto& [key, index] : path_keys_) {
      if (index >= 0) {
        out += "[" + std::to_string(index) + "]";
      } else {
        out += (out.empty() ? "" : ".") + key;
      }
    }
    return "in " + text::excerpt(out);
  }

  const std::string& path_;
  long long distinct_ = 0;
  std::unordered_map<int, std::vector<std::pair<YAML::Node, long long>>> seen_;
  std::vector<std::pair<std::string, long long>> path_keys_;  // key, or index of a list item
  std::vector<YAML::Node> open_;                              // the collections being walked, outermost first
};

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

YAML::Node parse_yaml(std::string_view text, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw Error("malformed YAML: " + e.msg, located(path, e.mark));
  }
  DocumentCheck(path).run(root);
  return root;
}

YAML::Node YamlReader::load(std::string_view text, const std::string& empty_message) const {
  YAML::Node root = parse_yaml(text, path_);
  if (!root.IsDefined() || root.IsNull()) throw Error(empty_message, {path_, 1, 1});
  return root;
}

std::vector<YamlReader::Entry> YamlReader::entries(const YAML::Node& map, const std::string& what) const {
  if (!map.IsMap()) fail(what + " must be a map", map);
  std::vector<Entry> out;
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (!it->first.IsScalar()) fail("a key of " + what + " must be a plain text", it->first);
    out.push_back({it->first.Scalar(), it->first, it->second});
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
