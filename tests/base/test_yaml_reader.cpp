// kg::parse_yaml, which every YAML the project reads goes through: duplicate keys anywhere are
// refused at the second one, and aliases cannot multiply a document.
#include <catch2/catch.hpp>

#include <chrono>
#include <string>

#include "kg/base/yaml_reader.hpp"

using Catch::Matchers::Contains;

namespace {

std::string error_of(const std::string& text) {
  try {
    kg::parse_yaml(text, "f.yaml");
  } catch (const kg::Error& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace

TEST_CASE("parse_yaml refuses a key given twice in any map, naming both places", "[yaml]") {
  CHECK(error_of("a: 1\nb: 2\na: 3\n") ==
        "f.yaml:3:1: duplicate key 'a' at the top level (first at f.yaml:1:1)");
  CHECK(error_of("constraints:\n  - {joint: lfoot, joint: nosuch}\n") ==
        "f.yaml:2:20: duplicate key 'joint' in 'constraints[0]' (first at f.yaml:2:6)");
  CHECK(error_of("patches:\n  - joint: a\npatches:\n  - joint: b\n") ==
        "f.yaml:3:1: duplicate key 'patches' at the top level (first at f.yaml:1:1)");
  CHECK(error_of("x:\n  y:\n    z: 1\n    z: 2\n") ==
        "f.yaml:4:5: duplicate key 'z' in 'x.y' (first at f.yaml:3:5)");
  CHECK(error_of("a: 1\nb: {a: 1, b: [1, {a: 2}]}\n") == "(accepted)");  // the same key in other maps
  CHECK(error_of("a: &x {k: 1, k: 2}\nb: *x\n") ==
        "f.yaml:1:14: duplicate key 'k' in 'a' (first at f.yaml:1:8)");
}

TEST_CASE("parse_yaml: a long or binary key is quoted short and escaped", "[yaml]") {
  const std::string key(500, 'k');  // YAML keys stop at 1024 characters
  const std::string message = error_of(key + ": 1\n" + key + ": 2\n");
  CHECK_THAT(message, Contains("duplicate key 'kkkk"));
  CHECK_THAT(message, Contains("... (500 bytes)"));
  CHECK(message.size() < 200);
}

TEST_CASE("parse_yaml refuses aliases that multiply a document (a billion laughs)", "[yaml]") {
  std::string text = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level <= 9; ++level) {
    text += "l" + std::to_string(level) + ": &l" + std::to_string(level) + " [";
    for (int k = 0; k < 10; ++k) text += std::string(k ? ", " : "") + "*l" + std::to_string(level - 1);
    text += "]\n";
  }
  const auto start = std::chrono::steady_clock::now();
  const std::string message = error_of(text);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK_THAT(message, Contains("f.yaml:1:1: aliases expand this document from "));
  CHECK_THAT(message, Contains("at most 1000000 more nodes through aliases"));
  CHECK(seconds < 5);  // each distinct node is visited once, however often it is named

  // A few aliases sharing params are fine.
  CHECK(error_of("p: &p {a: 1, b: 2}\nn1: {params: *p}\nn2: {params: *p}\n") == "(accepted)");
}

TEST_CASE("parse_yaml: a flow map as the first key of a block map is not mistaken for it", "[yaml]") {
  // Both start at offset 0; each is still checked as its own map.
  CHECK(error_of("{a: 1}: x\nb: 2\n") == "(accepted)");
  CHECK_THAT(error_of("{a: 1, a: 2}: x\n"), Contains("duplicate key 'a'"));
  CHECK_THAT(error_of("{a: 1}: x\n{a: 1}: y\n"), Contains("(accepted)"));  // non-scalar keys: not compared
}

TEST_CASE("parse_yaml: malformed YAML at its place, nesting beyond yaml-cpp's limit refused", "[yaml]") {
  CHECK_THAT(error_of("a: [1, 2\n"), Contains("f.yaml:"));
  CHECK_THAT(error_of("a: [1, 2\n"), Contains("malformed YAML"));
  CHECK_THAT(error_of(std::string(30000, '[') + std::string(30000, ']')), Contains("malformed YAML"));
}

TEST_CASE("parse_yaml refuses an alias inside the collection it names (a cycle), at its anchor", "[yaml]") {
  CHECK(error_of("a: &a {b: *a}\n") ==
        "f.yaml:1:4: an alias in 'a.b' names a collection that contains it (a cycle no reader can walk)");
  CHECK_THAT(
      error_of("nodes:\n  s: &p\n    params:\n      - {factor: *p}\n"),
      Contains("f.yaml:2:6: an alias in 'nodes.s.params[0].factor' names a collection that contains it"));
  CHECK_THAT(error_of("a: &a [1, [2, *a]]\n"), Contains("in 'a[1][1]' names a collection that contains it"));
  // The same collection named twice beside itself, not inside, is no cycle.
  CHECK(error_of("a: &a {b: 1}\nc: [*a, *a]\n") == "(accepted)");
}
