// Loads plugins (Boost.DLL) into a Registry. A library that fails to load, lacks the entry
// point, has another ABI version, throws from its entry, or registers a clashing name is
// refused with a clear message and leaves the registry as it was: the host keeps running.
//
// Where plugins come from, in this order (first plugin id loaded wins; later copies are skipped):
//   1. each --plugin-dir, 2. each directory of KINEGRAPH_PLUGIN_PATH (':'-separated),
//   3. the graph's `plugins:` entries: a path to a library or a directory (relative to the
//      graph file), or a bare name ("kg_lowpass") looked up in 1., 2. and the default
//      plugin directory beside the executable. An entry containing '/' or ending in ".so" is a
//      path; any other is a bare name N, found as N.so (or N) in a search directory.
//
//   PluginLoader loader(registry);
//   for (auto& problem : loader.load_directory("/opt/kg/plugins")) std::cerr << problem << '\n';
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "kg/graph/registry.hpp"

namespace kg::graph {

struct LoadedPlugin {
  std::string id;
  std::string version;
  std::filesystem::path path;
  std::size_t node_count = 0;
  std::size_t extension_count = 0;
};

class PluginLoader {
 public:
  explicit PluginLoader(Registry& registry) : registry_(registry) {}

  // Loads one library. Throws Error("<path>: <what went wrong>") when refused; a plugin whose id
  // is already loaded is not loaded twice (returns the first one's record).
  LoadedPlugin load_file(const std::filesystem::path& library);

  // Loads every shared library (*.so) directly in `dir`, in name order. Returns one message per
  // refused library; never throws for a bad library. A missing directory is one message.
  std::vector<std::string> load_directory(const std::filesystem::path& dir);

  // Resolves a graph's `plugins:` entry (see above) against `search_dirs`; throws Error naming
  // the entry and every place looked when not found.
  static std::filesystem::path resolve(const std::string& entry, const std::filesystem::path& graph_dir,
                                       const std::vector<std::filesystem::path>& search_dirs);

  const std::vector<LoadedPlugin>& loaded() const { return loaded_; }

 private:
  Registry& registry_;
  std::vector<LoadedPlugin> loaded_;
};

// Directories of KINEGRAPH_PLUGIN_PATH, in order (empty when unset).
std::vector<std::filesystem::path> plugin_path_from_environment();

}  // namespace kg::graph
