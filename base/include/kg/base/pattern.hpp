// Regular expressions a user supplies (in data files, params, the command line), compiled once
// with RE2 so that no pattern can crash, hang or exhaust the process: RE2 parses with an explicit
// stack (deep nesting is no stack overflow), matches in time linear in the text (no
// backtracking), and its memory is bounded per pattern. Every file or node that takes a pattern
// from a user goes through this class; fixed patterns of the code's own may too.
//
//   const kg::Pattern legs = kg::Pattern::compile("[lr](femur|tibia)");  // throws on a bad one
//   legs.full_match("lfemur");     // true: the whole text matches (std::regex_match)
//   legs.partial_match("xlfemur"); // true: some part matches (std::regex_search)
//
// Syntax: RE2's (https://github.com/google/re2/wiki/Syntax), which agrees with ECMAScript on
// what names need: literals, '.', classes [a-z] [^0-9] \d \w \s, alternation '|', groups ( )
// and (?: ), anchors ^ $ \b, quantifiers * + ? {n} {n,} {n,m} (lazy forms too), and adds (?i)
// for case-insensitive matching. It refuses backreferences (\1) and lookaround ((?= (?! (?<=),
// which need backtracking.
//
// Refused with std::invalid_argument, before or while compiling:
//   - a pattern longer than kMaxLength bytes (not compiled at all);
//   - a counted repetition whose count exceeds kMaxRepeat or has a leading zero ("a{1001}",
//     "a{99999999999999999999}", "a{01}"; RE2 alone would take the last two as literal text);
//   - one needing more than kMaxMemory bytes once compiled;
//   - any other syntax error RE2 reports (missing ), bad escape, lookahead, ...).
// The message quotes a short escaped excerpt of the pattern (text::excerpt), never all of it:
//   bad regular expression '((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((('...
//   (30000 bytes): longer than the 4096 bytes allowed
//   bad regular expression 'Left(?=Arm)': unsupported group '(?=' (RE2 has no lookahead or
//   lookbehind) (RE2 syntax: https://github.com/google/re2/wiki/Syntax)
// Callers put it at the place the pattern came from (YamlReader::pattern does so for a YAML node).
//
// Text is matched byte by byte (RE2's Latin-1 mode, as std::regex over char did): names are
// bytes, and a UTF-8 letter in a pattern is matched as the sequence of its bytes, so it matches
// the same letter in a name; inside a class [...] it stands for its separate bytes. Names that
// are not valid UTF-8 still match '.' and '.*'.
//
// kg::base links RE2 privately: this header does not show it, so code using Pattern needs no
// RE2 headers. A Pattern is immutable and cheap to copy (it shares the compiled program); it is
// safe to match from several threads at once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace re2 {
class RE2;
}

namespace kg {

class Pattern {
 public:
  // Longest pattern accepted, in bytes: room for an alternation of a hundred joint names.
  static constexpr std::size_t kMaxLength = 4096;
  // Largest count of a counted repetition {n,m} (RE2's own bound).
  static constexpr int kMaxRepeat = 1000;
  // Memory bound of one compiled pattern, in bytes (RE2's max_mem: its programs and the cache of
  // its lazily built DFA). A pattern whose program does not fit is refused as too large; a text
  // whose match would overflow the DFA cache is matched more slowly, never wrongly.
  static constexpr std::int64_t kMaxMemory = std::int64_t{1} << 20;

  // `text` compiled, or std::invalid_argument with a message as above.
  static Pattern compile(std::string_view text);

  // The pattern as given.
  const std::string& text() const;
  // Whether all of `s` matches (std::regex_match's sense).
  bool full_match(std::string_view s) const;
  // Whether some part of `s` matches, possibly empty (std::regex_search's sense).
  bool partial_match(std::string_view s) const;

 private:
  explicit Pattern(std::shared_ptr<const re2::RE2> re) : re_(std::move(re)) {}
  std::shared_ptr<const re2::RE2> re_;
};

}  // namespace kg
