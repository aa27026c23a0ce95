#include "host.hpp"

#include <signal.h>

#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/graph/yaml_io.hpp"

namespace kg::app {

namespace fs = std::filesystem;

void warn(const std::string& message) {
  std::cerr << "kinegraph: warning: " << message << '\n';
}

namespace {

extern "C" void interrupted(int sig) {
  kg::remove_pending_temporaries();
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

void remove_partial_outputs_on_signal() {
  struct sigaction action {};
  action.sa_handler = interrupted;
  ::sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &action, nullptr);
}

fs::path executable_path(const char* argv0) {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) exe = fs::absolute(argv0, ec);
  return exe;
}

fs::path install_prefix(const char* argv0) {
  return executable_path(argv0).parent_path().parent_path();
}

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

namespace {

void load_graph_plugins(Host& host, const graph::GraphDocument& document, const fs::path& file,
                        const std::map<std::string, std::string>& sets, bool allow_missing) {
  std::vector<graph::PluginEntry> entries;
  try {
    entries = document.plugins(sets, allow_missing);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  for (const auto& [entry, where] : entries) {
    try {
      const fs::path path = graph::PluginLoader::resolve(entry, file.parent_path(), host.search_dirs);
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

// The graph file parsed once, and the plugins it names loaded, as they provide node types.
graph::GraphDocument open_graph(Host& host, const fs::path& file,
                                const std::map<std::string, std::string>& sets, bool allow_missing) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    throw Failure{kExitGraphInvalid, file.string() + ": no such graph file"};
  }
  std::optional<graph::GraphDocument> document;
  try {
    document = graph::GraphDocument::from_file(file);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  load_graph_plugins(host, *document, file, sets, allow_missing);
  return *document;
}

}  // namespace

graph::Graph load_graph(Host& host, const fs::path& file, const std::map<std::string, std::string>& sets) {
  const graph::GraphDocument document = open_graph(host, file, sets, false);
  try {
    return document.load(host.registry, sets);
  } catch (const kg::Error& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, file.string() + ": " + e.what()};
  }
}

graph::GraphCheck check_graph(Host& host, const fs::path& file,
                              const std::map<std::string, std::string>& sets) {
  const graph::GraphDocument document = open_graph(host, file, sets, true);
  try {
    return document.check(host.registry, sets);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, file.string() + ": " + e.what()};
  }
}

std::vector<std::string> node_failures(const graph::Graph& g, const graph::RunResult& result) {
  std::vector<std::string> lines;
  for (const graph::NodeRun& n : result.nodes) {
    if (n.status != graph::NodeStatus::Failed) continue;
    const graph::NodeInstance* node = g.find_node(n.id);
    const std::string where = node ? node->where.to_string() : g.file.string();
    lines.push_back(where + ": node " + n.id + " (" + n.type + ") failed: " + n.message);
  }
  return lines;
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

}  // namespace kg::app
