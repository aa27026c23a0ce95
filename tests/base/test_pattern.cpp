// kg::Pattern (kg/base/pattern.hpp): RE2 for every user-supplied regular expression. Fuzzed
// patterns that crashed or overflowed std::regex are refused with a short message, in bounded
// time; the patterns of graphs/ and the data files mean what they meant under std::regex.
#include <catch2/catch.hpp>

#include <chrono>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "kg/base/pattern.hpp"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using kg::Pattern;

namespace {

// The message Pattern::compile throws for `text` ("" when it compiles).
std::string refusal(const std::string& text) {
  try {
    Pattern::compile(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("full_match is regex_match, partial_match is regex_search", "[pattern]") {
  const Pattern legs = Pattern::compile("[lr](femur|tibia)");
  CHECK(legs.full_match("lfemur"));
  CHECK_FALSE(legs.full_match("lfemurx"));
  CHECK_FALSE(legs.full_match("xlfemur"));
  CHECK(legs.partial_match("xlfemurx"));
  CHECK_FALSE(legs.partial_match("femur"));
  CHECK(legs.text() == "[lr](femur|tibia)");
  const Pattern copy = legs;  // copies share the program
  CHECK(copy.full_match("rtibia"));
  // Anchors, classes, counted repetitions, lazy forms, (?i).
  CHECK(Pattern::compile("^Left").partial_match("LeftArm"));
  CHECK_FALSE(Pattern::compile("^Arm").partial_match("LeftArm"));
  CHECK(Pattern::compile("Spine[0-9]+").full_match("Spine12"));
  CHECK(Pattern::compile("\\w+_[LR]").full_match("Hand_L"));
  CHECK(Pattern::compile("a{2,3}").full_match("aaa"));
  CHECK_FALSE(Pattern::compile("a{2,3}").full_match("aaaa"));
  CHECK(Pattern::compile("(?i)hips").full_match("Hips"));
  CHECK(Pattern::compile("").full_match(""));
  CHECK(Pattern::compile("").partial_match("anything"));
  // Bytes: a name that is not UTF-8 still matches '.', and a NUL is a byte like another.
  CHECK(Pattern::compile("l.*").full_match("l\xe9g"));
  CHECK(Pattern::compile("T\xc3\xaate").full_match("T\xc3\xaate"));
  CHECK(Pattern::compile(std::string("a\0b", 3)).full_match(std::string("a\0b", 3)));
}

TEST_CASE("the patterns of graphs/ and the default classes match as std::regex did", "[pattern]") {
  const std::vector<std::string> patterns{
      "[lr](tibia|foot|toes)|[lr](Shin|Foot)|(Left|Right)(Leg|Foot|ToeBase)",
      "lowerback|upperback|thorax|lowerneck|upperneck|head|abdomen|chest|neck|head|Spine|Chest|Neck|Head",
      "hip|[lr](Buttock|Thigh|Shin|Foot)",
      ".*(Eye|Jaw|Tongue|Teeth|FacialBone|Breast|RibsTwist|ShareBone).*",
      "(lower|upper)?neck|head|Neck[0-9]*|Head|CC_Base_Head|torso_head",
      "[lr](Foot|Toe)[A-Za-z]*[0-9]*|CC_Base_[LR]_([A-Za-z]*Toe[0-9]*)|(Left|Right)(Foot|ToeBase|Toe[A-Za-z_]"
      "*)",
      "arm|hand|Arm|Hand",
      "l.*",
      ".*",
  };
  const std::vector<std::string> names{"lfemur",
                                       "ltibia",
                                       "lfoot",
                                       "ltoes",
                                       "lShin",
                                       "LeftLeg",
                                       "LeftUpLeg",
                                       "LeftToeBase",
                                       "LeftToe_End",
                                       "Spine",
                                       "Spine1",
                                       "Neck",
                                       "neck",
                                       "upperneck",
                                       "head",
                                       "Head",
                                       "CC_Base_Head",
                                       "CC_Base_L_BigToe1",
                                       "hip",
                                       "hips",
                                       "lButtock",
                                       "rThigh",
                                       "LeftEye",
                                       "CC_Base_JawRoot",
                                       "RightHand",
                                       "LeftForeArm",
                                       "lhand",
                                       "root",
                                       "",
                                       "l",
                                       "Hips"};
  for (const std::string& p : patterns) {
    const Pattern re = Pattern::compile(p);
    const std::regex ecma(p, std::regex::ECMAScript);
    for (const std::string& name : names) {
      INFO(p << " on " << name);
      CHECK(re.full_match(name) == std::regex_match(name, ecma));
      CHECK(re.partial_match(name) == std::regex_search(name, ecma));
    }
  }
}

TEST_CASE("fuzzed patterns: refused with a short message, no crash, bounded time", "[pattern]") {
  const auto start = std::chrono::steady_clock::now();
  struct Case {
    std::string text;
    std::vector<std::string> says;
  };
  const std::vector<Case> cases{
      // Overflowed std::regex's recursive parser (SIGSEGV): refused for its length.
      {std::string(30000, '('),
       {"bad regular expression '((((", "... (30000 bytes)", "longer than the 4096"}},
      {std::string(30000, '(') + "a" + std::string(30000, ')'), {"(60001 bytes)", "longer than"}},
      // Signed overflow in libstdc++'s count; RE2 would take it as literal text.
      {"a{99999999999999999999}", {"'a{99999999999999999999}'", "repetition", "up to 1000"}},
      {"a{2,99999999999}", {"repetition '{2,99999999999}'"}},
      {"a{01}", {"leading zeros"}},
      {"a{1001}", {"repetition '{1001}'"}},
      // A 6 KB invalid pattern, and an invalid one under the limit: excerpts only.
      {std::string(6144, 'x') + "(", {"'xxxx", "... (6145 bytes)", "longer than"}},
      {std::string(3000, 'x') + "(", {"'xxxx", "... (3001 bytes)", "missing ) of the group", "RE2 syntax"}},
      {std::string(300, '(') + "a", {"missing )", "... (301 bytes)"}},
      // What ECMAScript has and RE2 refuses, and plain syntax errors.
      {"(a)\\1", {"backreference \\1"}},
      {"Left(?=Arm)", {"unsupported group '(?='", "lookahead"}},
      {"Left(", {"bad regular expression 'Left(': missing ) of the group 'Left('"}},
      {"a)", {"unexpected )"}},
      {"[lr", {"missing ]"}},
      {"[z-a]", {"bad range"}},
      {"*a", {"nothing to repeat"}},
      {"a**", {"bad repetition operator"}},
      {"a\\", {"a \\ at the end"}},
      {"\\y", {"bad escape '\\y'"}},
      {std::string("\x01\xff(", 3), {"'\\x01\\xff('"}},
      // Too large once compiled: counted repetitions nested within the length limit.
      {"((((a{1000}){1000}){1000}){1000})", {"bad regular expression"}},
  };
  for (const Case& c : cases) {
    const std::string message = refusal(c.text);
    INFO(message);
    REQUIRE(!message.empty());
    CHECK_THAT(message, StartsWith("bad regular expression '"));
    CHECK(message.size() < 300);
    for (const std::string& s : c.says) CHECK_THAT(message, Contains(s));
  }
  // Fine within the limits: escaped braces, braces in classes, \x{...}, counts up to 1000.
  for (const std::string ok : {"\\{99999999999}", "[{]99999999999}", "\\x{0041}", "a{1000}", "a{0,1000}",
                               "\\Q{01}\\E", "[[:alpha:]]{3}", "[]{]01}"}) {
    INFO(ok);
    CHECK(refusal(ok).empty());
  }
  CHECK(Pattern::compile("\\x{0041}").full_match("A"));
  CHECK(Pattern::compile("\\{99999999999}").full_match("{99999999999}"));
  // Deep but valid nesting within the length limit compiles and matches (RE2 parses with an
  // explicit stack).
  const Pattern deep = Pattern::compile(std::string(2000, '(') + "a" + std::string(2000, ')'));
  CHECK(deep.full_match("a"));
  // A pattern of the most expensive kind RE2 allows matches a long name in linear time.
  const Pattern heavy = Pattern::compile("(a|aa)*b");
  CHECK_FALSE(heavy.full_match(std::string(100000, 'a')));
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(10));
}
