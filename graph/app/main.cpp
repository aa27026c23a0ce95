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

#include "describe.hpp"
#include "kg/graph/error.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/plugin_abi.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/yaml_io.hpp"
#include "options.hpp"

namespace kg::app {
namespace {

namespace fs = std::filesystem;

// Thrown to leave with an exit code; `message` goes to stderr.
struct Failure {
  int code;
  std::string message;
};

void warn(const std::string& message) {
  std::cerr << "kinegraph: warning: " << message << '\n';
}

// The installation prefix: the executable lives in <prefix>/bin.
fs::path install_prefix(const char* argv0) {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) exe = fs::absolute(argv0, ec);
  return exe.parent_path().parent_path();
}

struct Host {
  graph::Registry registry;
  graph::PluginLoader loader{registry};
  std::vector<fs::path> search_dirs;  // for the graph's bare plugin names, in order
};

// Steps 1 to 3 of the plugin order (usage_text); step 4 needs the graph (load_graph_plugins).
void load_plugins(Host& host, const Options& o, const fs::path& prefix) {
  const fs::path builtin = prefix / "lib" / "kinegraph" / "kg_builtin_nodes.so";
  std::error_code ec;
  if (!fs::exists(builtin, ec)) {
    throw Failure{kExitPlugin,
                  "the built-in node module is missing: " + builtin.string() +
                      " (an incomplete build or installation: build the kg_builtin_nodes target)"};
  }
  try {
    host.loader.load_file(builtin);
  } catch (const std::exception& e) {
    throw Failure{kExitPlugin, std::string("cannot load the built-in node module: ") + e.what()};
  }
  for (const fs::path& dir : o.plugin_dirs) {
    for (const std::string& problem : host.loader.load_directory(dir)) warn(problem);
    host.search_dirs.push_back(dir);
  }
  for (const fs::path& dir : graph::plugin_path_from_environment()) {
    for (const std::string& problem : host.loader.load_directory(dir))
      warn(problem + " (from KINEGRAPH_PLUGIN_PATH)");
    host.search_dirs.push_back(dir);
  }
  host.search_dirs.push_back(prefix / "lib" / "kinegraph" / "plugins");
}

void load_graph_plugins(Host& host, const Options& o) {
  std::vector<graph::PluginEntry> entries;
  try {
    entries = graph::read_graph_plugins(o.graph, o.sets);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  for (const auto& [entry, where] : entries) {
    try {
      const fs::path path = graph::PluginLoader::resolve(entry, o.graph.parent_path(), host.search_dirs);
      if (fs::is_directory(path)) {
        for (const std::string& problem : host.loader.load_directory(path)) warn(problem);
      } else {
        host.loader.load_file(path);
      }
    } catch (const std::exception& e) {
      throw Failure{kExitPlugin, where.to_string() + ": plugins: " + e.what()};
    }
  }
}

graph::Graph load_graph(Host& host, const Options& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.graph, ec)) {
    throw Failure{kExitGraphInvalid, o.graph.string() + ": no such graph file"};
  }
  load_graph_plugins(host, o);
  try {
    return graph::load_graph(o.graph, host.registry, o.sets);
  } catch (const graph::Error& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, o.graph.string() + ": " + e.what()};
  }
}

std::string seconds(double s) {
  std::ostringstream os;
  if (s < 1) {
    os << std::fixed << std::setprecision(s < 0.01 ? 2 : 1) << s * 1000 << " ms";
  } else {
    os << std::fixed << std::setprecision(s < 10 ? 2 : 1) << s << " s";
  }
  return os.str();
}

int run(Host& host, const Options& o) {
  const graph::Graph g = load_graph(host, o);
  std::mutex log_mutex;
  graph::RunOptions options;
  options.jobs = o.jobs;
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
  for (const graph::NodeRun& n : result.nodes) {
    if (n.status != graph::NodeStatus::Failed) continue;
    const graph::NodeInstance* node = g.find_node(n.id);
    const std::string where = node ? node->where.to_string() : o.graph.string();
    std::cerr << "  " << where << ": node " << n.id << " (" << n.type << ") failed: " << n.message << '\n';
  }
  if (skipped > 0) {
    std::cerr << "  skipped:";
    for (const graph::NodeRun& n : result.nodes) {
      if (n.status == graph::NodeStatus::Skipped) std::cerr << ' ' << n.id;
    }
    std::cerr << '\n';
  }
  return code;
}

int dispatch(const Options& o, const char* argv0) {
  switch (o.verb) {
    case Verb::Help:
      std::cout << usage_text();
      return kExitOk;
    case Verb::Version:
      std::cout << "kinegraph " << KG_VERSION << " (plugin ABI " << graph::kPluginAbiVersion
                << ", graph format " << graph::kGraphFormatVersion << ")\n";
      return kExitOk;
    default:
      break;
  }
  Host host;
  load_plugins(host, o, install_prefix(argv0));
  switch (o.verb) {
    case Verb::Run:
      return run(host, o);
    case Verb::Validate: {
      const graph::Graph g = load_graph(host, o);
      std::cout << o.graph.string() << ": valid: " << g.nodes.size() << " nodes, " << g.connections.size()
                << " connections\n";
      return kExitOk;
    }
    case Verb::Dot: {
      const graph::Graph g = load_graph(host, o);
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
    std::cerr << "kinegraph: " << e.what() << "\n"
              << "usage: kinegraph run|validate|dot GRAPH [options], kinegraph nodes [--json]; see kinegraph "
                 "--help\n";
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
