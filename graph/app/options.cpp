#include "options.hpp"

#include <charconv>
#include <optional>

#include "kg/graph/error.hpp"

namespace kg::app {
namespace {

struct VerbName {
  const char* name;
  Verb verb;
};
constexpr VerbName kVerbs[] = {
    {"run", Verb::Run}, {"validate", Verb::Validate}, {"nodes", Verb::Nodes}, {"dot", Verb::Dot}};

const char* verb_name(Verb verb) {
  for (const VerbName& v : kVerbs) {
    if (v.verb == verb) return v.name;
  }
  return "";
}

bool takes_graph(Verb verb) {
  return verb == Verb::Run || verb == Verb::Validate || verb == Verb::Dot;
}

int parse_jobs(const std::string& text) {
  int jobs = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), jobs);
  if (ec != std::errc() || end != text.data() + text.size() || jobs < 1 || jobs > 1024) {
    throw UsageError("--jobs expects a whole number from 1 to 1024, got '" + text + "'");
  }
  return jobs;
}

}  // namespace

std::string usage_text() {
  return R"(kinegraph: runs Kinegraph node graphs (YAML files wiring motion-processing nodes).

usage:
  kinegraph run GRAPH [--set NAME=VALUE]... [--jobs N] [--report FILE] [--plugin-dir DIR]...
  kinegraph validate GRAPH [--set NAME=VALUE]... [--plugin-dir DIR]...
  kinegraph nodes [--json] [--plugin-dir DIR]...
  kinegraph dot GRAPH [--set NAME=VALUE]... [--plugin-dir DIR]...
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

options:
  --set NAME=VALUE  give the graph variable NAME a value (GRAPH documents its variables at the top)
  --jobs N          run independent branches on up to N threads (default 1)
  --report FILE     write per-node status, wall times and reported figures as JSON to FILE
  --plugin-dir DIR  load every plugin (*.so) directly in DIR; may be repeated
  --json            nodes: print JSON instead of text

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

Messages go to stderr; `nodes` and `dot` write to stdout.
)";
}

Options parse_options(int argc, const char* const* argv) {
  Options o;
  std::optional<Verb> verb;
  bool help = false, version = false, jobs_given = false;
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
      given.push_back({name, {Verb::Run, Verb::Validate, Verb::Dot}});
    } else if (name == "--jobs" || name == "-j") {
      if (jobs_given) throw UsageError("--jobs is given twice");
      o.jobs = parse_jobs(take_value());
      jobs_given = true;
      given.push_back({"--jobs", {Verb::Run}});
    } else if (name == "--report") {
      if (!o.report.empty()) throw UsageError("--report is given twice");
      o.report = take_value();
      if (o.report.empty()) throw UsageError("--report needs a file name");
      given.push_back({name, {Verb::Run}});
    } else if (name == "--plugin-dir") {
      const std::string dir = take_value();
      if (dir.empty()) throw UsageError("--plugin-dir needs a directory");
      o.plugin_dirs.emplace_back(dir);
      given.push_back({name, {Verb::Run, Verb::Validate, Verb::Nodes, Verb::Dot}});
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
  if (positionals.empty()) throw UsageError("no verb given: run, validate, nodes or dot");
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
    const std::string near = kg::graph::nearest_name(verb_text, names);
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
  } else if (positionals.size() > 1) {
    throw UsageError("unexpected argument '" + positionals[1] + "'");
  }
  return o;
}

}  // namespace kg::app
