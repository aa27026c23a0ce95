// Test support: the joint-name patterns fuzzing found to crash or overflow std::regex, for the
// tests of every file and node that takes patterns (they now go through kg::Pattern, RE2). Each
// must be refused with a message naming its place and quoting a short excerpt of it only, with
// no crash and in bounded time. YAML allows implicit keys of at most 1024 characters (yaml-cpp:
// "illegal map value"), so a file gives a longer pattern as an explicit key ("? key", then
// ": value" on the next line), as the fuzzer's files did:
//
//   for (const kg::test::FuzzedPattern& p : kg::test::fuzzed_patterns()) {
//     const std::string text = "version: 1\nbones:\n" + kg::test::explicit_entry(p.text, "1", 2);
//     kg::test::check_refusal(message_of_reading(text), "bad.yaml:3:5: bones: ", p);
//   }
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

namespace kg::test {

struct FuzzedPattern {
  std::string name;     // what it is, for INFO
  std::string text;     // the pattern; no '"' or '\', so it can go in a YAML "..." key as it is
  std::string excerpt;  // what a message quotes of it
};

inline std::vector<FuzzedPattern> fuzzed_patterns() {
  return {
      // std::regex's recursive parser overflowed the stack (SIGSEGV).
      {"30,000 nested parentheses", std::string(30000, '('),
       "'" + std::string(60, '(') + "'... (30000 bytes)"},
      // Signed overflow in libstdc++'s regex compiler.
      {"a repetition count overflowing int", "a{99999999999999999999}", "'a{99999999999999999999}'"},
      // Quoted whole, 6 KB, in the message.
      {"a 6 KB invalid pattern", std::string(6143, 'x') + "(",
       "'" + std::string(60, 'x') + "'... (6144 bytes)"},
  };
}

// `pattern: value` as an entry of a YAML block map indented by `indent` spaces, with an explicit
// key of any length; the key's node starts at column indent + 3 of the entry's first line.
inline std::string explicit_entry(const std::string& pattern, const std::string& value, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  return pad + "? \"" + pattern + "\"\n" + pad + ": " + value + "\n";
}

// The longest message a refused pattern may give, the file name and the place included.
constexpr std::size_t kMaxRefusalLength = 400;

// A refusal of `pattern`: starts with `prefix` (file:line:column: and what), says "bad regular
// expression" with the excerpt, and is short.
inline void check_refusal(const std::string& message, const std::string& prefix,
                          const FuzzedPattern& pattern) {
  INFO(pattern.name << ": " << message);
  CHECK_THAT(message,
             Catch::StartsWith(prefix) && Catch::Contains("bad regular expression " + pattern.excerpt));
  CHECK(message.size() < kMaxRefusalLength);
}

// Seconds since `start`, for the bounded-time checks.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace kg::test
