// The CLI's host: the registry, the plugins loaded into it, and the graph loading every verb
// shares. Problems leave through Failure with the exit code documented in options.hpp.
//
//   Host host;
//   load_plugins(host, options, install_prefix(argv[0]));
//   graph::Graph g = load_graph(host, options.graph, options.sets);
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "kg/graph/executor.hpp"
#include "kg/graph/graph.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/yaml_io.hpp"
#include "options.hpp"

namespace kg::app {

// Thrown to leave with an exit code; `message` goes to stderr.
struct Failure {
  int code;
  std::string message;
};

void warn(const std::string& message);

// From now on SIGINT, SIGTERM and SIGHUP remove the temporary files of outputs being written,
// then end the process as the signal would: an interrupted run leaves no partial output.
void remove_partial_outputs_on_signal();

// The installation prefix: the executable lives in <prefix>/bin.
std::filesystem::path install_prefix(const char* argv0);
// The running executable, absolute.
std::filesystem::path executable_path(const char* argv0);

struct Host {
  graph::Registry registry;
  graph::PluginLoader loader{registry};
  std::vector<std::filesystem::path> search_dirs;  // for the graph's bare plugin names, in order
};

// Steps 1 to 3 of the plugin order (usage_text); step 4 needs the graph (load_graph).
void load_plugins(Host& host, const Options& o, const std::filesystem::path& prefix);

// Loads the plugins `file` names (step 4), then the graph with `sets` as its variables.
graph::Graph load_graph(Host& host, const std::filesystem::path& file,
                        const std::map<std::string, std::string>& sets);

// What `validate` reports: as load_graph, with every problem collected, the required variables
// given no value listed rather than refused, and input paths checked (graph::GraphDocument::check).
graph::GraphCheck check_graph(Host& host, const std::filesystem::path& file,
                              const std::map<std::string, std::string>& sets);

// "graphs/x.yaml:12:3: node solve (retarget.spacetime) failed: ..." for each node that failed.
std::vector<std::string> node_failures(const graph::Graph& g, const graph::RunResult& result);

// "12.3 ms", "1.23 s", "12.3 s".
std::string seconds(double s);

}  // namespace kg::app
