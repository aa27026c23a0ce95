#include "options.hpp"

#include <charconv>
#include <optional>

#include "kg/base/error.hpp"

namespace kg::app {
namespace {

struct VerbName {
  const char* name;
  Verb verb;
};
constexpr VerbName kVerbs[] = {{"run", Verb::Run}, {"validate", Verb::Validate}, {"nodes", Verb::Nodes},
                               {"dot", Verb::Dot}, {"batch", Verb::Batch},       {"merge", Verb::Merge}};

const char* verb_name(Verb verb) {
  for (const VerbName& v : kVerbs) {
    if (v.verb == verb) return v.name;
  }
  return "";
}

bool takes_graph(Verb verb) {
  return verb == Verb::Run || verb == Verb::Validate || verb == Verb::Dot || verb == Verb::Batch;
}

std::optional<int> whole_number(const std::string& text) {
  int n = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return n;
}

int parse_count(const std::string& option, const std::string& text, int most) {
  const std::optional<int> n = whole_number(text);
  if (!n || *n < 1 || *n > most) {
    throw UsageError(option + " expects a whole number from 1 to " + std::to_string(most) + ", got '" + text +
                     "'");
  }
  return *n;
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  const std::optional<int> index = whole_number(text.substr(0, slash));
  const std::optional<int> count =
      slash == std::string::npos ? std::nullopt : whole_number(text.substr(slash + 1));
  if (!index || !count || *count < 1 || *index < 0 || *index >= *count) {
    throw UsageError("--shard expects I/N with 0 <= I < N (e.g. 0/4 for the first of four), got '" + text +
                     "'");
  }
  return {*index, *count};
}

}  // namespace

std::string usage_text() {
  return R"(kinegraph: runs Kinegraph node graphs (YAML files wiring motion-processing nodes).

usage:
  kinegraph run GRAPH [--set NAME=VALUE]... [--jobs N] [--report FILE] [--reproducible]
                [--plugin-dir DIR]...
  kinegraph validate GRAPH [--set NAME=VALUE]... [--plugin-dir DIR]...
  kinegraph nodes [--json] [--plugin-dir DIR]...
  kinegraph dot GRAPH [--set NAME=VALUE]... [--plugin-dir DIR]...
  kinegraph batch GRAPH --inputs PATTERN... --out DIR [--jobs N] [--set NAME=VALUE]... [--force]
                  [--shard I/N] [--input-list FILE] [--plugin-dir DIR]...
  kinegraph batch GRAPH --inputs PATTERN... --out DIR --slurm SCRIPT [--shards N]
                  [--sbatch OPTION]... [--submit] [--jobs N] [--set NAME=VALUE]...
  kinegraph merge DIR
  kinegraph --help | --version

verbs:
  run       check GRAPH completely, then run it; a failing node is reported with its id and
            its downstream nodes are skipped, the other branches still run
  validate  check GRAPH (node types, ports, port types, params, variables) without running it
  nodes     list every node type: ports with types, params with types, defaults, ranges,
            choices and docs, and where each type comes from (built-ins, the plugins shipped
            in <prefix>/lib/kinegraph/plugins, and those of --plugin-dir and KINEGRAPH_PLUGIN_PATH)
  dot       print GRAPH as Graphviz, ports and their types on the edges:
            kinegraph dot GRAPH | dot -Tsvg > graph.svg
  batch     run GRAPH once per input file, up to --jobs items at once, each in its own process
            with the variables input (the file), stem (its name without extension) and out
            (the item's folder: DIR/stem, or DIR/sub/stem for an input in sub/ below the
            inputs' common folder). Largest inputs start first. Writes DIR/logs/ITEM.log per
            item and a manifest,
            DIR/manifest.jsonl (DIR/manifest.shard-I-of-N.jsonl with --shard), one JSON line per
            item: status, wall time, outputs with their SHA-256, the figures the graph reports,
            and the hashes of input, graph and settings. Items already done with the same
            hashes and outputs in place are skipped (--force redoes them). Ctrl-C stops at
            once, removes partial outputs, and keeps the manifest: the same command continues.
            With --slurm, writes an sbatch array script (one task per shard) and a merge job
            script instead of running (--submit also submits them, the merge after the array)
  merge     merge the shard manifests in DIR into DIR/manifest.jsonl and report what failed or
            is missing

options:
  --set NAME=VALUE  give the graph variable NAME a value (GRAPH documents its variables at the top)
  --jobs N          run: independent branches on up to N threads (default 1); batch: items at
                    once (default: the cores this process may use; with --slurm, the CPUs
                    of each array task, default 1)
  --report FILE     write per-node status, wall times and reported figures as JSON to FILE
  --reproducible    run: files written come out byte for byte the same on every run and machine
                    (no wall-clock times in them; those stay in --report); batch always is
  --plugin-dir DIR  load every plugin (*.so) directly in DIR; may be repeated
  --json            nodes: print JSON instead of text
  --inputs PATTERN...  batch: input files, as paths or patterns: * ? [..] within a folder name,
                    ** for any depth of folders (quote them so the shell leaves them alone);
                    every argument up to the next option (a '-' word) is a pattern
  --input-list FILE batch: input files listed in FILE, one per line (with or without --inputs)
  --out DIR         batch: the folder of item outputs, logs and the manifest
  --force           batch: redo items already done
  --shard I/N       batch: run only items I, I+N, I+2N, ... of the sorted inputs (0 <= I < N)
  --slurm SCRIPT    batch: write SCRIPT, an sbatch array job, and SCRIPT's merge job beside it
  --shards N        with --slurm: array tasks (default: one per 8 items, at most 100)
  --sbatch OPTION   with --slurm: an #SBATCH line for both jobs (--sbatch=--partition=short)
  --submit          with --slurm: submit the array, then the merge depending on it

plugins, loaded in this order (a plugin id loaded once is not loaded again):
  1. the built-in nodes, <prefix>/lib/kinegraph/kg_builtin_nodes.so beside this program
  2. each --plugin-dir
  3. each directory of KINEGRAPH_PLUGIN_PATH (':'-separated)
  4. GRAPH's `plugins:` entries: a path to a library or a directory (containing a '/' or
     ending in .so; relative to GRAPH's directory), or a bare name (kg_lowpass) looked for as
     NAME.so in 2., 3. and <prefix>/lib/kinegraph/plugins
  A bad library in a plugin directory is reported as a warning and skipped.

exit codes:
  0  success
  1  a node failed during run (or the --report file could not be written)
  2  usage error
  3  the graph is invalid: it cannot be read or fails validation
  4  plugin error: the built-in node module, or a plugin GRAPH names, cannot be loaded
  batch and merge: 1 when any item failed (or, merging, has no record); 130 when interrupted

Messages go to stderr; `nodes` and `dot` write to stdout.
)";
}

Options parse_options(int argc, const char* const* argv) {
  Options o;
  std::optional<Verb> verb;
  bool help = false, version = false;
  std::vector<std::string> positionals;
  // Options given, with the verbs they apply to: checked once the verb is known.
  std::vector<std::pair<std::string, std::vector<Verb>>> given;

  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--") {
      for (++i; i < argc; ++i) positionals.emplace_back(argv[i]);
      break;
    }
    if (arg.size() < 2 || arg[0] != '-') {
      positionals.push_back(arg);
      continue;
    }
    std::string name = arg, value;
    bool has_value = false;
    if (auto eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string::npos) {
      name = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_value = true;
    }
    auto take_value = [&]() -> std::string {
      if (has_value) return value;
      if (i + 1 >= argc) throw UsageError(name + " needs a value");
      return argv[++i];
    };
    if (name == "--help" || name == "-h") {
      help = true;
    } else if (name == "--version") {
      version = true;
    } else if (name == "--set") {
      const std::string setting = take_value();
      const auto eq = setting.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw UsageError("--set expects NAME=VALUE, got '" + setting + "'");
      }
      const std::string key = setting.substr(0, eq);
      if (!o.sets.emplace(key, setting.substr(eq + 1)).second) {
        throw UsageError("--set " + key + " is given twice");
      }
      given.push_back({name, {Verb::Run, Verb::Validate, Verb::Dot, Verb::Batch}});
    } else if (name == "--jobs" || name == "-j") {
      if (o.jobs_given) throw UsageError("--jobs is given twice");
      o.jobs = parse_count("--jobs", take_value(), 1024);
      o.jobs_given = true;
      given.push_back({"--jobs", {Verb::Run, Verb::Batch}});
    } else if (name == "--reproducible") {
      if (has_value) throw UsageError("--reproducible takes no value");
      o.reproducible = true;
      given.push_back({name, {Verb::Run}});
    } else if (name == "--inputs") {
      if (has_value) {
        o.inputs.push_back(value);
      } else {
        // Up to the next option: anything starting with '-' but a lone "-".
        for (; i + 1 < argc && (argv[i + 1][0] != '-' || argv[i + 1][1] == 0); ++i)
          o.inputs.emplace_back(argv[i + 1]);
      }
      if (o.inputs.empty()) throw UsageError("--inputs needs at least one file or pattern");
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--input-list") {
      if (!o.input_list.empty()) throw UsageError("--input-list is given twice");
      o.input_list = take_value();
      if (o.input_list.empty()) throw UsageError("--input-list needs a file name");
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--out") {
      if (!o.out.empty()) throw UsageError("--out is given twice");
      o.out = take_value();
      if (o.out.empty()) throw UsageError("--out needs a folder");
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--force") {
      if (has_value) throw UsageError("--force takes no value");
      o.force = true;
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--shard") {
      if (o.shard) throw UsageError("--shard is given twice");
      o.shard = parse_shard(take_value());
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--slurm") {
      if (!o.slurm.empty()) throw UsageError("--slurm is given twice");
      o.slurm = take_value();
      if (o.slurm.empty()) throw UsageError("--slurm needs a script file name");
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--shards") {
      if (o.shards) throw UsageError("--shards is given twice");
      o.shards = parse_count("--shards", take_value(), 10000);
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--sbatch") {
      const std::string option = take_value();
      if (option.empty())
        throw UsageError("--sbatch needs an sbatch option, e.g. --sbatch=--partition=short");
      if (option.find('\n') != std::string::npos) throw UsageError("--sbatch option has a line break");
      o.sbatch_options.push_back(option);
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--submit") {
      if (has_value) throw UsageError("--submit takes no value");
      o.submit = true;
      given.push_back({name, {Verb::Batch}});
    } else if (name == "--report") {
      if (!o.report.empty()) throw UsageError("--report is given twice");
      o.report = take_value();
      if (o.report.empty()) throw UsageError("--report needs a file name");
      given.push_back({name, {Verb::Run}});
    } else if (name == "--plugin-dir") {
      const std::string dir = take_value();
      if (dir.empty()) throw UsageError("--plugin-dir needs a directory");
      o.plugin_dirs.emplace_back(dir);
      given.push_back({name, {Verb::Run, Verb::Validate, Verb::Nodes, Verb::Dot, Verb::Batch}});
    } else if (name == "--json") {
      if (has_value) throw UsageError("--json takes no value");
      o.json = true;
      given.push_back({name, {Verb::Nodes}});
    } else {
      throw UsageError("unknown option '" + arg + "'");
    }
  }

  if (help) {
    o.verb = Verb::Help;
    return o;
  }
  if (version) {
    o.verb = Verb::Version;
    return o;
  }
  if (positionals.empty()) throw UsageError("no verb given: run, validate, nodes, dot, batch or merge");
  const std::string& verb_text = positionals.front();
  for (const VerbName& v : kVerbs) {
    if (verb_text == v.name) verb = v.verb;
  }
  if (verb_text == "help") {
    o.verb = Verb::Help;
    return o;
  }
  if (!verb) {
    std::vector<std::string> names;
    for (const VerbName& v : kVerbs) names.emplace_back(v.name);
    const std::string near = kg::nearest_name(verb_text, names);
    throw UsageError("unknown verb '" + verb_text + "'" +
                     (near.empty() ? "" : "; did you mean '" + near + "'?"));
  }
  o.verb = *verb;
  for (const auto& [option, verbs] : given) {
    bool ok = false;
    for (Verb v : verbs) ok = ok || v == o.verb;
    if (!ok) throw UsageError(option + " does not apply to " + verb_name(o.verb));
  }
  if (takes_graph(o.verb)) {
    if (positionals.size() < 2) throw UsageError(std::string(verb_name(o.verb)) + " needs a GRAPH file");
    if (positionals.size() > 2) throw UsageError("unexpected argument '" + positionals[2] + "'");
    o.graph = positionals[1];
  } else if (o.verb == Verb::Merge) {
    if (positionals.size() < 2) throw UsageError("merge needs the batch's DIR");
    if (positionals.size() > 2) throw UsageError("unexpected argument '" + positionals[2] + "'");
    o.out = positionals[1];
  } else if (positionals.size() > 1) {
    throw UsageError("unexpected argument '" + positionals[1] + "'");
  }
  if (o.verb == Verb::Batch) {
    if (o.inputs.empty() && o.input_list.empty())
      throw UsageError("batch needs --inputs PATTERN... or --input-list FILE");
    if (o.out.empty()) throw UsageError("batch needs --out DIR");
    if (o.slurm.empty() && (o.shards || !o.sbatch_options.empty() || o.submit)) {
      throw UsageError("--shards, --sbatch and --submit go with --slurm SCRIPT");
    }
    if (!o.slurm.empty() && o.shard)
      throw UsageError("--shard and --slurm do not go together (each array task is a shard)");
    for (const char* own : {"input", "stem", "out"}) {
      if (o.sets.count(own)) {
        throw UsageError(std::string("--set ") + own + "=...: batch sets the variable " + own +
                         " for each item itself");
      }
    }
  }
  return o;
}

}  // namespace kg::app
