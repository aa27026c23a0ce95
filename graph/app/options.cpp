#include "options.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <iterator>
#include <optional>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"

namespace kg::app {
namespace {

struct VerbName {
  const char* name;
  Verb verb;
  const char* doc;  // the verb's line in its own --help
};
constexpr VerbName kVerbs[] = {
    {"run", Verb::Run, "check GRAPH completely, then run it"},
    {"validate", Verb::Validate,
     "check GRAPH without running it: every problem it has, the values a run needs, inputs given"},
    {"nodes", Verb::Nodes, "list every node type: ports, params, defaults, ranges, choices, docs and origin"},
    {"dot", Verb::Dot, "print GRAPH as Graphviz: kinegraph dot GRAPH | dot -Tsvg > graph.svg"},
    {"batch", Verb::Batch, "run GRAPH once per input file, each item in its own process, with a manifest"},
    {"merge", Verb::Merge, "merge the shard manifests in DIR into DIR/manifest.jsonl"},
    {"inspect", Verb::Inspect,
     "the motion doctor: CLIP's joints, rate, up axis, units, calibration frames, footplants, flights and "
     "their gravity, floor penetration, pops, and the --set values that fix what it found"},
    {"map", Verb::Map,
     "propose a skeleton map from SOURCE's skeleton to TARGET's (each a clip, an .asf or a URDF): the chains "
     "found on each with their evidence, what matched and what did not; --out writes the map to edit"}};

const char* verb_name(Verb verb) {
  for (const VerbName& v : kVerbs) {
    if (v.verb == verb) return v.name;
  }
  return "";
}

// The positional a verb takes: GRAPH, merge's DIR, or none.
const char* operand_of(Verb verb) {
  if (verb == Verb::Run || verb == Verb::Validate || verb == Verb::Dot || verb == Verb::Batch) return "GRAPH";
  if (verb == Verb::Inspect) return "CLIP";
  if (verb == Verb::Map) return "SOURCE";
  return verb == Verb::Merge ? "DIR" : nullptr;
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

// A path option given once and not empty.
void set_path_once(std::filesystem::path& field, const char* option, const std::string& value,
                   const char* needs) {
  if (!field.empty()) throw UsageError(std::string(option) + " is given twice");
  if (value.empty()) throw UsageError(std::string(option) + " needs " + needs);
  field = value;
}

void apply_set(Options& o, const std::string& setting) {
  const auto eq = setting.find('=');
  if (eq == std::string::npos || eq == 0)
    throw UsageError("--set expects NAME=VALUE, got " + text::in_quotes(setting));
  const std::string key = setting.substr(0, eq);
  if (!o.sets.emplace(key, setting.substr(eq + 1)).second)
    throw UsageError("--set " + key + " is given twice");
}

void apply_jobs(Options& o, const std::string& value) {
  if (o.jobs_given) throw UsageError("--jobs is given twice");
  o.jobs = parse_count("--jobs", value, 1024);
  o.jobs_given = true;
}

void apply_shard(Options& o, const std::string& value) {
  if (o.shard) throw UsageError("--shard is given twice");
  o.shard = parse_shard(value);
}

void apply_shards(Options& o, const std::string& value) {
  if (o.shards) throw UsageError("--shards is given twice");
  o.shards = parse_count("--shards", value, 10000);
}

void apply_sbatch(Options& o, const std::string& option) {
  if (option.empty()) throw UsageError("--sbatch needs an sbatch option, e.g. --sbatch=--partition=short");
  if (option.find('\n') != std::string::npos) throw UsageError("--sbatch option has a line break");
  o.sbatch_options.push_back(option);
}

void apply_plugin_dir(Options& o, const std::string& dir) {
  if (dir.empty()) throw UsageError("--plugin-dir needs a directory");
  o.plugin_dirs.emplace_back(dir);
}

// Verbs as a set of bits.
using VerbSet = unsigned;
constexpr VerbSet in(Verb verb) {
  return 1u << static_cast<unsigned>(verb);
}
constexpr VerbSet kGraphVerbs = in(Verb::Run) | in(Verb::Validate) | in(Verb::Dot) | in(Verb::Batch);

// An option of the command line: what it takes, the verbs it applies to, and what a value does.
struct OptionSpec {
  const char* name;        // "--jobs"
  const char* short_name;  // "-j", or ""
  const char* value;       // its value in the help ("N"); "" for a flag
  const char* doc;
  VerbSet verbs;
  void (*apply)(Options&, const std::string& value);  // called per value, in the order given
  bool list = false;                                  // takes every argument up to the next option (--inputs)
};

// Shorthands for the lambdas of the table.
using O = Options;
using S = const std::string&;
constexpr OptionSpec kOptions[] = {
    {"--set", "", "NAME=VALUE", "give the graph variable NAME a value (GRAPH documents its variables)",
     kGraphVerbs | in(Verb::Inspect), apply_set},
    {"--jobs", "-j", "N",
     "run: independent branches on up to N threads (default 1); batch: items at once (default: the "
     "cores this process may use; with --slurm, the CPUs of each array task, default 1)",
     in(Verb::Run) | in(Verb::Batch), apply_jobs},
    {"--report", "", "FILE", "write per-node status, wall times and reported figures as JSON to FILE",
     in(Verb::Run), [](O& o, S v) { set_path_once(o.report, "--report", v, "a file name"); }},
    {"--reproducible", "", "",
     "files written come out byte for byte the same on every run and machine (no wall-clock times)",
     in(Verb::Run), [](O& o, S) { o.reproducible = true; }},
    {"--plugin-dir", "", "DIR", "load every plugin (*.so) directly in DIR; may be repeated",
     kGraphVerbs | in(Verb::Nodes) | in(Verb::Inspect) | in(Verb::Map), apply_plugin_dir},
    {"--json", "", "", "print JSON instead of text", in(Verb::Nodes) | in(Verb::Inspect),
     [](O& o, S) { o.json = true; }},
    {"--skeleton", "", "ASF",
     "inspect, map: the .asf of an .amc CLIP or SOURCE (default: <subject>.asf beside it)",
     in(Verb::Inspect) | in(Verb::Map),
     [](O& o, S v) { set_path_once(o.skeleton, "--skeleton", v, "an .asf file"); }},
    {"--target-skeleton", "", "ASF", "map: the .asf of an .amc TARGET (default: <subject>.asf beside it)",
     in(Verb::Map),
     [](O& o, S v) { set_path_once(o.target_skeleton, "--target-skeleton", v, "an .asf file"); }},
    {"--inputs", "", "PATTERN...",
     "input files, as paths or patterns: * ? [..] within a folder name, ** for any depth of folders "
     "(quoted); every argument up to the next option is a pattern",
     in(Verb::Batch), [](O& o, S v) { o.inputs.push_back(v); }, true},
    {"--input-list", "", "FILE", "input files listed in FILE, one per line (with or without --inputs)",
     in(Verb::Batch), [](O& o, S v) { set_path_once(o.input_list, "--input-list", v, "a file name"); }},
    {"--out", "", "PATH",
     "batch: the folder of item outputs, logs and the manifest; map: the map file to write (YAML)",
     in(Verb::Batch) | in(Verb::Map), [](O& o, S v) { set_path_once(o.out, "--out", v, "a folder"); }},
    {"--force", "", "", "redo items already done", in(Verb::Batch), [](O& o, S) { o.force = true; }},
    {"--shard", "", "I/N", "run only items I, I+N, I+2N, ... of the sorted inputs (0 <= I < N)",
     in(Verb::Batch), apply_shard},
    {"--slurm", "", "SCRIPT", "write SCRIPT, an sbatch array job, and SCRIPT's merge job beside it",
     in(Verb::Batch), [](O& o, S v) { set_path_once(o.slurm, "--slurm", v, "a script file name"); }},
    {"--shards", "", "N", "with --slurm: array tasks (default: one per 8 items, at most 100)",
     in(Verb::Batch), apply_shards},
    {"--sbatch", "", "OPTION", "with --slurm: an #SBATCH line for both jobs (--sbatch=--partition=short)",
     in(Verb::Batch), apply_sbatch},
    {"--submit", "", "", "with --slurm: submit the array, then the merge depending on it", in(Verb::Batch),
     [](O& o, S) { o.submit = true; }},
};

bool applies(const OptionSpec& spec, Verb verb) {
  return (spec.verbs & in(verb)) != 0;
}

CLI::Option* add_option(CLI::App& app, const OptionSpec& spec) {
  const std::string names = *spec.short_name ? std::string(spec.short_name) + "," + spec.name : spec.name;
  CLI::Option* option = *spec.value ? app.add_option(names) : app.add_flag(names);
  option->description(spec.doc)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  if (*spec.value) option->type_name(spec.value);
  if (spec.list) option->expected(1, -1)->allow_extra_args();
  return option;
}

// A verb's --help as CLI11 lays it out, but for the usage line: CLI11 2.1 would also show the
// hidden catch-all positional there.
class VerbHelp : public CLI::Formatter {
 public:
  std::string make_usage(const CLI::App* app, std::string name) const override {
    std::string usage = get_label("Usage") + ": " + name;
    for (const CLI::Option* operand : app->get_options(
             [](const CLI::Option* o) { return o->get_positional() && !o->get_group().empty(); }))
      usage += " " + operand->get_name();
    if (!app->get_options([](const CLI::Option* o) { return o->nonpositional() && !o->get_group().empty(); })
             .empty())
      usage += " [OPTIONS]";
    return usage + "\n";
  }
};

// The command line as CLI11 sees it: a subcommand per verb with the options that apply to it and
// its positional. Every option is also on the top level, hidden, where the subcommands fall
// through to: so options may come before the verb, and one given to a verb it does not apply to
// is recognised, to be refused by name.
struct CommandLine {
  CLI::App app{"kinegraph: runs Kinegraph node graphs", "kinegraph"};
  CLI::Option* help = nullptr;
  CLI::Option* version = nullptr;
  struct Verbs {
    Verb verb;
    CLI::App* app;
    std::string operand;  // its GRAPH or DIR
    CLI::Option* operand_option = nullptr;
    std::string second_operand;  // map's TARGET
    CLI::Option* second_operand_option = nullptr;
    std::vector<std::string> extra;     // arguments beyond it
    std::vector<CLI::Option*> options;  // per kOptions: nullptr when it does not apply
  };
  std::vector<Verbs> verbs;       // kVerbs, then help; reserved: CLI11 holds references into them
  std::vector<CLI::Option*> top;  // per kOptions, on the top level

  CommandLine() {
    app.set_help_flag();
    app.allow_extras();            // unknown options and arguments are named by parse_options
    app.require_subcommand(0, 1);  // a verb's argument named like a verb is an argument
    help = app.add_flag("-h,--help")->group("");
    version = app.add_flag("--version")->group("");
    for (const OptionSpec& spec : kOptions) top.push_back(add_option(app, spec)->group(""));
    verbs.reserve(std::size(kVerbs) + 1);
    for (const VerbName& v : kVerbs) add_verb(v.verb, v.name, v.doc);
    add_verb(Verb::Help, "help", "");
    verbs.back().app->group("");
  }

  void add_verb(Verb verb, const char* name, const char* doc) {
    CLI::App* sub = app.add_subcommand(name, doc);
    sub->fallthrough();
    sub->formatter(std::make_shared<VerbHelp>());
    sub->footer("Plugin search order and exit codes: kinegraph --help");
    Verbs& v = verbs.emplace_back(Verbs{verb, sub, {}, nullptr, {}, {}});
    if (const char* operand = operand_of(verb)) {
      v.operand_option = sub->add_option(operand, v.operand,
                                         verb == Verb::Merge     ? "the batch's folder"
                                         : verb == Verb::Inspect ? "the clip (.bvh or .amc)"
                                         : verb == Verb::Map     ? "the source: a clip, an .asf or a URDF"
                                                                 : "the graph file (YAML)")
                             ->type_name("");
    }
    if (verb == Verb::Map)
      v.second_operand_option =
          sub->add_option("TARGET", v.second_operand, "the target: a clip, an .asf or a URDF")->type_name("");
    sub->add_option("extra", v.extra)->group("");
    sub->add_flag("-h,--help")->group("");
    for (const OptionSpec& spec : kOptions)
      v.options.push_back(applies(spec, verb) ? add_option(*sub, spec) : nullptr);
  }

  const Verbs* given_verb() const {
    for (const Verbs& v : verbs) {
      if (v.app->parsed()) return &v;
    }
    return nullptr;
  }
};

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
  kinegraph inspect CLIP [--skeleton ASF] [--json] [--set NAME=VALUE]... [--plugin-dir DIR]...
  kinegraph map SOURCE TARGET [--out MAP.yaml] [--skeleton ASF] [--target-skeleton ASF]
                [--plugin-dir DIR]...
  kinegraph --help | --version

verbs:
  run       check GRAPH completely, then run it; a failing node is reported with its id and
            its downstream nodes are skipped, the other branches still run
  validate  check GRAPH (node types, ports, port types, params, variables, input files given)
            without running it; reports every problem, and names the required variables a run
            still needs (the params they reach are checked once they are given)
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
  inspect   the motion doctor: CLIP (.bvh, or .amc with --skeleton) read with every frame, then
            its joint tree, frames and rate, the up axis and unit it was read with, calibration
            frames, footplants per foot point and their skate, flights and the gravity each
            implies (and the true rate when the header's is off by a whole factor), floor
            penetration, pops, and the --set values that fix what it found; --json prints the
            motion.inspect report. --set units=, up= and source_fps= read the clip otherwise
  map       propose a skeleton map from SOURCE to TARGET (each a clip, an .asf or a URDF): the
            chains found on each (pelvis, spine, neck, legs, arms) with their evidence, what was
            paired and what was not; --out writes the map (YAML) to edit

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

namespace {

// The arguments after the program, in the reverse order CLI11 parses them from. Two forms CLI11
// 2.1 reads otherwise than Kinegraph always has: `--name=` (an empty value) would be `--name` with
// its value still to come, so it is split into `--name` and "", and the option refuses the empty
// value as before; `--flag=VALUE` would set or clear the flag, so it is refused.
std::vector<std::string> arguments_of(int argc, const char* const* argv) {
  std::vector<std::string> args;
  bool options_end = false;  // after "--" every argument is a positional
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    options_end = options_end || arg == "--";
    const auto eq = arg.find('=');
    const auto spec = std::find_if(std::begin(kOptions), std::end(kOptions), [&](const OptionSpec& s) {
      return !options_end && eq != std::string::npos && arg.compare(0, eq, s.name) == 0 &&
             std::strlen(s.name) == eq;
    });
    if (spec != std::end(kOptions) && !*spec->value)
      throw UsageError(std::string(spec->name) + " takes no value");
    if (spec != std::end(kOptions) && eq + 1 == arg.size()) {
      args.push_back(spec->name);
      args.emplace_back();
    } else {
      args.push_back(arg);
    }
  }
  std::reverse(args.begin(), args.end());
  return args;
}

// CLI11 stops at an option whose value is missing ("--jobs: 1 required N missing").
std::string parse_error_message(const CLI::ParseError& e) {
  const std::string what = e.what();
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e)) {
    for (const OptionSpec& spec : kOptions) {
      if (what.rfind(std::string(spec.name) + ":", 0) != 0) continue;
      return spec.list ? std::string(spec.name) + " needs at least one file or pattern"
                       : std::string(spec.name) + " needs a value";
    }
  }
  return what;
}

// What CLI11 left over: options nobody knows, and arguments before the verb.
std::vector<std::string> refuse_unknown_options(const CommandLine& cli) {
  std::vector<std::string> arguments;
  for (const std::string& arg : cli.app.remaining()) {
    if (arg.size() > 1 && arg[0] == '-') throw UsageError("unknown option " + text::in_quotes(arg));
    arguments.push_back(arg);
  }
  return arguments;
}

// Every value of every option, top level first (given before the verb), then the verb's own.
void apply_values(const CommandLine& cli, Options& o) {
  const CommandLine::Verbs* verb = cli.given_verb();
  const auto& specs = kOptions;
  for (std::size_t i = 0; i < std::size(specs); ++i) {
    std::vector<std::string> values = cli.top[i]->results();
    if (verb && verb->options[i]) {
      for (const std::string& v : verb->options[i]->results()) values.push_back(v);
    }
    for (const std::string& value : values) specs[i].apply(o, value);
  }
}

// The verb: the first argument, which CLI11 took as a subcommand unless it is none.
Verb verb_of(const CommandLine& cli, const std::vector<std::string>& before_verb) {
  if (before_verb.empty()) {
    if (const CommandLine::Verbs* v = cli.given_verb()) return v->verb;
    throw UsageError("no verb given: run, validate, nodes, dot, batch or merge");
  }
  std::vector<std::string> names;
  for (const VerbName& v : kVerbs) names.emplace_back(v.name);
  const std::string& text = before_verb.front();
  const std::string near = kg::nearest_name(text, names);
  throw UsageError("unknown verb '" + text + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?"));
}

// An option given before the verb, or after it to a verb it does not apply to.
void check_options_apply(const CommandLine& cli, Verb verb) {
  const auto& specs = kOptions;
  for (std::size_t i = 0; i < std::size(specs); ++i) {
    if (cli.top[i]->count() > 0 && !applies(specs[i], verb))
      throw UsageError(std::string(specs[i].name) + " does not apply to " + verb_name(verb));
  }
}

// GRAPH or merge's DIR, and nothing after it.
void take_operand(const CommandLine::Verbs& v, Options& o) {
  if (const char* operand = operand_of(v.verb)) {
    if (v.operand_option->count() == 0) {
      throw UsageError(v.verb == Verb::Merge
                           ? std::string("merge needs the batch's DIR")
                           : std::string(verb_name(v.verb)) + " needs a " + operand + " file" +
                                 (v.verb == Verb::Inspect ? " (.bvh, or .amc)" : ""));
    }
    (v.verb == Verb::Merge                            ? o.out
     : v.verb == Verb::Inspect || v.verb == Verb::Map ? o.clip
                                                      : o.graph) = v.operand;
  }
  if (v.verb == Verb::Map) {
    if (v.second_operand_option->count() == 0) throw UsageError("map needs a SOURCE and a TARGET file");
    o.map_target = v.second_operand;
  }
  if (!v.extra.empty()) throw UsageError("unexpected argument '" + v.extra.front() + "'");
}

void check_batch(const Options& o) {
  if (o.inputs.empty() && o.input_list.empty())
    throw UsageError("batch needs --inputs PATTERN... or --input-list FILE");
  if (o.out.empty()) throw UsageError("batch needs --out DIR");
  if (o.slurm.empty() && (o.shards || !o.sbatch_options.empty() || o.submit))
    throw UsageError("--shards, --sbatch and --submit go with --slurm SCRIPT");
  if (!o.slurm.empty() && o.shard)
    throw UsageError("--shard and --slurm do not go together (each array task is a shard)");
  for (const char* own : {"input", "stem", "out"}) {
    if (o.sets.count(own)) {
      throw UsageError(std::string("--set ") + own + "=...: batch sets the variable " + own +
                       " for each item itself");
    }
  }
}

}  // namespace

Options parse_options(int argc, const char* const* argv) {
  CommandLine cli;
  try {
    cli.app.parse(arguments_of(argc, argv));
  } catch (const CLI::ParseError& e) {
    throw UsageError(parse_error_message(e));
  }
  const std::vector<std::string> before_verb = refuse_unknown_options(cli);
  Options o;
  apply_values(cli, o);
  const CommandLine::Verbs* given = cli.given_verb();
  if (cli.help->count() > 0 || (given && given->app->get_option("--help")->count() > 0)) {
    o.verb = Verb::Help;
    if (given && before_verb.empty()) o.help_topic = given->verb;
    return o;
  }
  if (cli.version->count() > 0) {
    o.verb = Verb::Version;
    return o;
  }
  o.verb = verb_of(cli, before_verb);
  if (o.verb == Verb::Help) return o;
  check_options_apply(cli, o.verb);
  take_operand(*given, o);
  if (o.verb == Verb::Batch) check_batch(o);
  return o;
}

std::string verb_usage_text(Verb verb) {
  CommandLine cli;
  for (const CommandLine::Verbs& v : cli.verbs) {
    if (v.verb == verb && verb != Verb::Help) return v.app->help("kinegraph");
  }
  return usage_text();
}

}  // namespace kg::app
