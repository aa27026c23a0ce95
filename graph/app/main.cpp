// kinegraph: the command-line host. It knows node types only through the registry: the built-in
// ones arrive as the first module loaded through the same PluginLoader as every other plugin
// (<prefix>/lib/kinegraph/kg_builtin_nodes.so), so nothing here includes nodes/.
// Verbs, options and exit codes: options.hpp (usage_text() is the --help text).
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "batch.hpp"
#include "describe.hpp"
#include "host.hpp"
#include "kg/base/error.hpp"
#include "kg/base/report.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/plugin_abi.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/yaml_io.hpp"
#include "options.hpp"

namespace kg::app {
namespace {

namespace fs = std::filesystem;

int run(Host& host, const Options& o) {
  const graph::Graph g = load_graph(host, o.graph, o.sets);
  std::mutex log_mutex;
  graph::RunOptions options;
  options.jobs = o.jobs;
  options.reproducible = o.reproducible;
  options.keep_outputs = false;  // the sinks have written the files: free each value after its last consumer
  options.on_log = [&log_mutex](const std::string& node, const std::string& message) {
    std::lock_guard lock(log_mutex);
    std::cerr << node << ": " << message << '\n';
  };
  const graph::RunResult result = graph::run_graph(g, host.registry, options);

  int code = result.ok ? kExitOk : kExitNodeFailed;
  if (!o.report.empty()) {
    try {
      graph::write_report_json(o.report, g, result);
    } catch (const std::exception& e) {
      std::cerr << "kinegraph: cannot write the report: " << e.what() << '\n';
      code = kExitNodeFailed;
    }
  }
  if (result.ok) {
    std::cout << o.graph.string() << ": " << result.nodes.size() << " nodes ran in "
              << seconds(result.wall_seconds) << '\n';
    return code;
  }
  std::size_t failed = 0, skipped = 0;
  for (const graph::NodeRun& n : result.nodes) {
    failed += n.status == graph::NodeStatus::Failed;
    skipped += n.status == graph::NodeStatus::Skipped;
  }
  std::cerr << "kinegraph: " << o.graph.string() << ": run failed: " << failed << " of "
            << result.nodes.size() << " nodes failed, " << skipped << " skipped ("
            << seconds(result.wall_seconds) << ")\n";
  for (const std::string& failure : node_failures(g, result)) std::cerr << "  " << failure << '\n';
  if (skipped > 0) {
    std::cerr << "  skipped:";
    for (const graph::NodeRun& n : result.nodes) {
      if (n.status == graph::NodeStatus::Skipped) std::cerr << ' ' << n.id;
    }
    std::cerr << '\n';
  }
  return code;
}

// `inspect`: the clip read with every frame by the importer every graph uses, then motion.inspect.
constexpr const char* kInspectGraph = R"(version: 1
doc: kinegraph inspect CLIP
variables:
  input: {required: true}
  skeleton: {default: ""}
  units: {default: "auto"}
  up: {default: "auto"}
  source_fps: {default: "0"}
  trim: {default: "none"}
nodes:
  source:
    type: io.import_motion
    params: {path: "${input}", skeleton: "${skeleton}", units: "${units}", up: "${up}", fps: "${source_fps}", trim: "${trim}"}
  inspect: {type: motion.inspect}
connections:
  - {from: source.motion, to: inspect.motion}
)";

int inspect(Host& host, const Options& o) {
  std::map<std::string, std::string> sets = o.sets;
  for (const char* fixed : {"input", "skeleton"})
    if (sets.count(fixed))
      throw Failure{kExitUsage, std::string("inspect: give the ") + fixed + " as " +
                                    (fixed == std::string("input") ? "CLIP" : "--skeleton")};
  sets["input"] = o.clip.string();
  sets["skeleton"] = o.skeleton.string();
  graph::Graph g;
  try {
    g = graph::load_graph_from_string(kInspectGraph, "kinegraph inspect", host.registry, sets);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  std::vector<std::string> notes;
  graph::RunOptions options;
  options.on_log = [&](const std::string& node, const std::string& message) {
    // inspect's own lines are its report's summary; a failure is printed below
    if (node == "source" && message.rfind("failed: ", 0) != 0) notes.push_back(message);
  };
  const graph::RunResult result = graph::run_graph(g, host.registry, options);
  if (!result.ok) {
    for (const std::string& note : notes) std::cerr << note << '\n';
    for (const graph::NodeRun& n : result.nodes)
      if (n.status == graph::NodeStatus::Failed)
        std::cerr << "kinegraph: inspect " << o.clip.string() << ": " << n.message << '\n';
    return kExitNodeFailed;
  }
  const Report& report = result.outputs.at("inspect.report").get<Report>();
  if (o.json) {
    for (const std::string& note : notes) std::cerr << note << '\n';
    report.write(std::cout);
    std::cout << '\n';
    return kExitOk;
  }
  for (const std::string& note : notes) std::cout << "read: " << note << '\n';
  for (const std::string& line : report.strings("summary")) std::cout << line << '\n';
  return kExitOk;
}

constexpr const char* kMapGraph = R"(version: 1
doc: kinegraph map SOURCE TARGET
variables:
  source: {required: true}
  source_skeleton: {default: ""}
  target: {required: true}
  target_skeleton: {default: ""}
  out: {default: ""}
nodes:
  source:
    type: io.import_motion
    params: {path: "${source}", skeleton: "${source_skeleton}", trim: "none"}
  target:
    type: io.import_motion
    params: {path: "${target}", skeleton: "${target_skeleton}", trim: "none"}
  map:
    type: retarget.propose_map
    params: {source_file: "${source}", target_file: "${target}"}
  write:
    type: retarget.write_map
    params: {path: "${out}"}
connections:
  - {from: source.motion, to: map.source}
  - {from: target.motion, to: map.target}
  - {from: map.map, to: write.map}
)";

// Prints what was matched, what was not and how each chain was found; writes --out.
int map(Host& host, const Options& o) {
  const std::map<std::string, std::string> sets = {{"source", o.clip.string()},
                                                   {"source_skeleton", o.skeleton.string()},
                                                   {"target", o.map_target.string()},
                                                   {"target_skeleton", o.target_skeleton.string()},
                                                   {"out", o.out.string()}};
  graph::Graph g;
  try {
    g = graph::load_graph_from_string(kMapGraph, "kinegraph map", host.registry, sets);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  std::vector<std::string> read, how;
  graph::RunOptions options;
  options.on_log = [&](const std::string& node, const std::string& message) {
    if (message.rfind("failed: ", 0) == 0 || node == "write") return;
    (node == "map" ? how : read).push_back(message);
  };
  const graph::RunResult result = graph::run_graph(g, host.registry, options);
  for (const std::string& note : read) std::cout << "read: " << note << '\n';
  if (!result.ok) {
    for (const graph::NodeRun& n : result.nodes)
      if (n.status == graph::NodeStatus::Failed) std::cerr << "kinegraph: map: " << n.message << '\n';
    return kExitNodeFailed;
  }
  for (const std::string& line : how) std::cout << "found: " << line << '\n';
  const Report& report = result.outputs.at("map.report").get<Report>();
  for (const std::string& line : report.strings("summary")) std::cout << line << '\n';
  if (o.out.empty()) {
    std::cout << "(not written: give --out MAP.yaml to write the map)\n";
  } else {
    std::cout << "wrote " << o.out.string() << '\n';
  }
  return kExitOk;
}

// Every problem, one line each; a graph without problems is valid even when a run needs values.
int validate(Host& host, const Options& o) {
  const graph::GraphCheck check = check_graph(host, o.graph, o.sets);
  for (const kg::Error& problem : check.problems) std::cerr << "kinegraph: " << problem.what() << '\n';
  if (!check.problems.empty()) {
    std::cerr << "kinegraph: " << o.graph.string() << ": invalid: " << check.problems.size()
              << (check.problems.size() == 1 ? " problem" : " problems") << '\n';
    return kExitGraphInvalid;
  }
  std::cout << o.graph.string() << ": valid: " << check.graph.nodes.size() << " nodes, "
            << check.graph.connections.size() << " connections\n";
  if (!check.needed.empty()) {
    std::cout << "a run needs:";
    for (const graph::Variable& v : check.needed) std::cout << " --set " << v.name << "=...";
    std::cout << '\n';
    for (const graph::Variable& v : check.needed)
      if (!v.doc.empty()) std::cout << "  " << v.name << ": " << v.doc << '\n';
    std::cout << "(params that use them are checked when they are given)\n";
  }
  return kExitOk;
}

int dispatch(const Options& o, const char* argv0) {
  switch (o.verb) {
    case Verb::Help:
      std::cout << verb_usage_text(o.help_topic);
      return kExitOk;
    case Verb::Version:
      std::cout << "kinegraph " << KG_VERSION << " (plugin ABI " << graph::kPluginAbiVersion
                << ", graph format " << graph::kGraphFormatVersion << ")\n";
      return kExitOk;
    case Verb::Merge:
      return merge(o);
    default:
      break;
  }
  remove_partial_outputs_on_signal();
  Host host;
  load_plugins(host, o, install_prefix(argv0));
  switch (o.verb) {
    case Verb::Run:
      return run(host, o);
    case Verb::Batch:
      return batch(host, o, argv0);
    case Verb::Validate:
      return validate(host, o);
    case Verb::Inspect:
      return inspect(host, o);
    case Verb::Map:
      return map(host, o);
    case Verb::Dot: {
      const graph::Graph g = load_graph(host, o.graph, o.sets);
      write_dot(std::cout, g, host.registry);
      return kExitOk;
    }
    case Verb::Nodes:
      // Every node type the user can reach: the shipped plugins too, which graphs name in `plugins:`.
      for (const std::string& problem : host.loader.load_directory(host.search_dirs.back())) warn(problem);
      if (o.json) {
        print_nodes_json(std::cout, host.registry, host.loader.loaded());
      } else {
        print_nodes_text(std::cout, host.registry);
      }
      return kExitOk;
    default:
      return kExitUsage;
  }
}

}  // namespace
}  // namespace kg::app

int main(int argc, char** argv) {
  using namespace kg::app;
  Options options;
  try {
    options = parse_options(argc, argv);
  } catch (const UsageError& e) {
    std::cerr
        << "kinegraph: " << e.what() << "\n"
        << "usage: kinegraph run|validate|dot|batch GRAPH [options], kinegraph nodes [--json], "
           "kinegraph merge DIR, kinegraph inspect CLIP, kinegraph map SOURCE TARGET; see kinegraph --help\n";
    return kExitUsage;
  }
  try {
    const int code = dispatch(options, argv[0]);
    std::cout.flush();
    return code;
  } catch (const Failure& f) {
    std::cout.flush();
    std::cerr << "kinegraph: " << f.message << '\n';
    return f.code;
  } catch (const std::exception& e) {
    std::cerr << "kinegraph: unexpected error: " << e.what() << '\n';
    return kExitNodeFailed;
  }
}
