// Errors of loading and wiring (tier 1 of DESIGN.md): thrown before anything runs, always naming
// where the problem is. Node failures (tier 2) are plain exceptions caught by the executor; solver
// outcomes (tier 3) are data on a node's outputs.
//
//   throw kg::Error("graph has a cycle: a -> b -> a", {"graphs/x.yaml", 12, 3});
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace kg {

// A place in a text file. line and column are 1-based; 0 means unknown.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;

  // "file:line:column", "file:line", "file", or "" when nothing is known.
  std::string to_string() const;
};

// what() is "file:line:column: message" (the location part omitted when unknown).
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message, SourceLocation where = {});
  const std::string& message() const { return message_; }
  const SourceLocation& where() const { return where_; }

 private:
  std::string message_;
  SourceLocation where_;
};

// Closest candidate by edit distance, or "" when none is reasonably close (used for "did you mean").
std::string nearest_name(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace kg
