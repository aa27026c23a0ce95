// The kinegraph command line: verbs, options, usage text and exit codes.
//
//   Options o = parse_options(argc, argv);   // throws UsageError
//   if (o.verb == Verb::Run) ...
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace kg::app {

// Documented in the usage text; scripts rely on them.
enum ExitCode : int {
  kExitOk = 0,
  kExitNodeFailed = 1,     // a node failed during `run` (or the report could not be written)
  kExitUsage = 2,          // bad command line
  kExitGraphInvalid = 3,   // the graph cannot be read or fails validation
  kExitPlugin = 4,         // the built-in node module or a plugin the graph names cannot be loaded
  kExitInterrupted = 130,  // batch: stopped by SIGINT or SIGTERM; running it again continues
};

enum class Verb { Help, Version, Run, Validate, Nodes, Dot, Batch, Merge, Inspect, Map };

// --shard I/N: items whose position in the sorted input list is I modulo N (0 <= I < N).
struct Shard {
  int index = 0;
  int count = 1;
};

struct Options {
  Verb verb = Verb::Help;
  Verb help_topic = Verb::Help;                    // Help: the verb whose --help was asked for
  std::filesystem::path graph;                     // run, validate, dot, batch
  std::map<std::string, std::string> sets;         // --set NAME=VALUE
  int jobs = 1;                                    // --jobs N (run: threads; batch: items at once)
  bool jobs_given = false;                         // batch defaults jobs to the cores it may use
  std::filesystem::path report;                    // --report FILE (run); empty: none
  std::vector<std::filesystem::path> plugin_dirs;  // --plugin-dir DIR, in order
  bool json = false;                               // --json (nodes, inspect)
  std::filesystem::path clip;                      // inspect's CLIP, map's SOURCE
  std::filesystem::path skeleton;                  // --skeleton ASF (inspect, map)
  std::filesystem::path map_target;                // map's TARGET
  std::filesystem::path target_skeleton;           // --target-skeleton ASF (map)
  bool reproducible = false;                       // --reproducible (run; batch always is)

  // batch
  std::vector<std::string> inputs;          // --inputs PATTERN... (file_patterns.hpp)
  std::filesystem::path input_list;         // --input-list FILE: one input path per line
  std::filesystem::path out;                // --out DIR (batch), FILE (map); the DIR argument of merge
  bool force = false;                       // --force: redo items already done
  std::optional<Shard> shard;               // --shard I/N
  std::filesystem::path slurm;              // --slurm SCRIPT: write sbatch scripts instead of running
  int shards = 0;                           // --shards N (with --slurm; 0: one per 8 items, at most 100)
  std::vector<std::string> sbatch_options;  // --sbatch OPTION, an #SBATCH line each
  bool submit = false;                      // --submit: with --slurm, also submit both jobs
};

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// argv[0] is the program. Parsed by CLI11: a subcommand per verb. Options may come before or after
// the verb; `--name value` and `--name=value` are both accepted. Throws UsageError naming the
// offending argument.
Options parse_options(int argc, const char* const* argv);

// The whole --help text (verbs, options, plugin search order, exit codes).
std::string usage_text();

// `kinegraph VERB --help`: the verb's operand and the options that apply to it (CLI11's layout);
// usage_text() for Verb::Help.
std::string verb_usage_text(Verb verb);

}  // namespace kg::app
