// The kinegraph command line: verbs, options, usage text and exit codes.
//
//   Options o = parse_options(argc, argv);   // throws UsageError
//   if (o.verb == Verb::Run) ...
#pragma once

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace kg::app {

// Documented in the usage text; scripts rely on them.
enum ExitCode : int {
  kExitOk = 0,
  kExitNodeFailed = 1,    // a node failed during `run` (or the report could not be written)
  kExitUsage = 2,         // bad command line
  kExitGraphInvalid = 3,  // the graph cannot be read or fails validation
  kExitPlugin = 4,        // the built-in node module or a plugin the graph names cannot be loaded
};

enum class Verb { Help, Version, Run, Validate, Nodes, Dot };

struct Options {
  Verb verb = Verb::Help;
  std::filesystem::path graph;                     // run, validate, dot
  std::map<std::string, std::string> sets;         // --set NAME=VALUE
  int jobs = 1;                                    // --jobs N (run)
  std::filesystem::path report;                    // --report FILE (run); empty: none
  std::vector<std::filesystem::path> plugin_dirs;  // --plugin-dir DIR, in order
  bool json = false;                               // --json (nodes)
};

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// argv[0] is the program. Options may come before or after the verb; `--name value` and
// `--name=value` are both accepted. Throws UsageError naming the offending argument.
Options parse_options(int argc, const char* const* argv);

// The whole --help text (verbs, options, plugin search order, exit codes).
std::string usage_text();

}  // namespace kg::app
