// Strict reading of the project's versioned YAML data files (target characters, body models,
// ...): every error is a kg::Error located at file:line:column; map entries come in file
// order with duplicate keys refused; unknown keys are refused with the nearest allowed one;
// numbers must be finite; regular expressions are compiled where they are read, a bad one
// failing at its place. A file's own reader derives from YamlReader and adds its keys.
//
//   class TargetReader : public kg::YamlReader { ... };
//   TargetReader r("short_legs.yaml");
//   YAML::Node root = r.load(text, "empty target file (expected version: 1 and bones)");
//   const auto top = r.entries(root, "the target file");
//   r.check_keys(top, "the target file", {"version", "bones"});
//   r.check_version(top);
//
// kg::base links yaml-cpp publicly: this header is over its nodes.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "kg/base/error.hpp"
#include "kg/base/pattern.hpp"

namespace kg {

// Every YAML text the project reads (graph files and every data file) is parsed here, so that no
// reader can forget a check: malformed YAML fails at its mark (yaml-cpp also refuses nesting
// deeper than 2,000); a map giving one key twice fails at the second one, naming the first; and
// aliases may not make the document larger than its own nodes plus kMaxYamlAliasGrowth nodes (a
// "billion laughs" of nested aliases is refused before any reader walks it). `path` names the
// file in messages. Returns a null node for an empty document.
inline constexpr long long kMaxYamlAliasGrowth = 1'000'000;
YAML::Node parse_yaml(std::string_view text, const std::string& path);

class YamlReader {
 public:
  explicit YamlReader(std::string path) : path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  // Where a node starts (1-based line and column; the file alone when unknown).
  SourceLocation at(const YAML::Node& node) const;
  [[noreturn]] void fail(const std::string& message, const YAML::Node& where) const;
  [[noreturn]] void fail(const std::string& message, const YAML::Mark& where) const;

  // The document through parse_yaml; an empty document fails with `empty_message`.
  YAML::Node load(std::string_view text, const std::string& empty_message) const;

  struct Entry {
    std::string key;
    YAML::Node key_node, value;
  };
  // A map's entries in file order; `what` names the map in messages ("the body file",
  // "segments.lfemur"). Keys must be scalars (parse_yaml has made them distinct).
  std::vector<Entry> entries(const YAML::Node& map, const std::string& what) const;
  // Refuses keys outside `allowed`, naming the nearest allowed one.
  void check_keys(const std::vector<Entry>& entries, const std::string& what,
                  const std::vector<std::string>& allowed) const;
  // The same for a map read by key lookups: a key is named by its dotted path in the message
  // ("constraints[0].pionts"; `path` "" for the top level).
  void check_keys(const YAML::Node& map, const std::string& path,
                  const std::vector<std::string>& allowed) const;
  // Requires `version: 1` among the top-level entries.
  void check_version(const std::vector<Entry>& top) const;
  // The entry of `key`, or null.
  static const Entry* find(const std::vector<Entry>& entries, const std::string& key);

  // A finite number; with allow_infinite also +-.inf / +-inf (YAML's and C's spellings).
  double number(const YAML::Node& node, const std::string& what, bool allow_infinite = false) const;
  double positive(const YAML::Node& node, const std::string& what) const;      // > 0
  double non_negative(const YAML::Node& node, const std::string& what) const;  // >= 0
  int integer(const YAML::Node& node, const std::string& what) const;
  std::string text(const YAML::Node& node, const std::string& what) const;  // a scalar
  // A user's regular expression (kg/base/pattern.hpp: RE2 syntax, bounded length) from a scalar
  // (a map key's node too), compiled; a bad one fails at the node as
  // "what: bad regular expression '<short excerpt>': why".
  Pattern pattern(const YAML::Node& node, const std::string& what) const;

 private:
  std::string path_;
};

}  // namespace kg
