// Plugin loading with Boost.DLL. The order of checks matters: the ABI version is read before the
// entry is called, because a record built against other headers cannot be read safely. Nothing
// reaches the registry until the whole record has been checked, so a refused plugin leaves it as
// it was.
//
// Lifetime: a plugin's code must outlive everything made from it. Rather than relying on the
// order in which other containers destroy their members, every factory and node is wrapped here
// in a host-side object that holds the library and destroys the plugin's object first; each
// extension's object and every value a plugin node outputs are tied to the library through
// Extension::kept_alive_by and Value::kept_alive_by.
#include "kg/graph/plugin_loader.hpp"

#include <dlfcn.h>
#include <elf.h>
#include <link.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

#include <boost/dll/shared_library.hpp>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/graph/plugin_abi.hpp"

namespace kg::graph {
namespace {

namespace fs = std::filesystem;
using Library = boost::dll::shared_library;

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KG_LEAK_CHECKED_AT_EXIT 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define KG_LEAK_CHECKED_AT_EXIT 1
#endif

// LeakSanitizer looks for leaks after the libraries are unloaded. Libraries a plugin pulls in
// keep memory reachable only from their own data (gflags' flag registry through glog, libgomp's
// state), which unloading unmaps: it would be reported as leaked, without a symbol. Under
// AddressSanitizer plugins stay mapped, so that what it reports is ours.
#ifdef KG_LEAK_CHECKED_AT_EXIT
constexpr int kExtraLoadFlags = RTLD_NODELETE;
#else
constexpr int kExtraLoadFlags = 0;
#endif

[[noreturn]] void refuse(const fs::path& path, const std::string& what) {
  throw Error(what, SourceLocation{path.string()});
}

int symbol_type(const ElfW(Sym) & symbol) {
#if __ELF_NATIVE_CLASS == 64
  return ELF64_ST_TYPE(symbol.st_info);
#else
  return ELF32_ST_TYPE(symbol.st_info);
#endif
}

// The alias symbols BOOST_DLL_ALIAS exports are data: a pointer to the function. A library that
// exports a plain function under the same name would have its code read as a pointer, so check
// the symbol's ELF type, that it is the plugin's own and that the pointer lands inside the
// plugin before calling it.
template <class Fn>
Fn* alias_function(const Library& lib, const char* name, const fs::path& path) {
  void* symbol = dlsym(lib.native(), name);
  if (symbol == nullptr) refuse(path, std::string("no ") + name + " symbol: not a Kinegraph plugin");
  Dl_info info{};
  ElfW(Sym)* entry = nullptr;
  if (dladdr1(symbol, &info, reinterpret_cast<void**>(&entry), RTLD_DL_SYMENT) == 0 || entry == nullptr ||
      symbol_type(*entry) != STT_OBJECT || entry->st_size != sizeof(void*)) {
    refuse(path, std::string(name) +
                     " is not a Boost.DLL alias (a pointer to a function); export it with KG_PLUGIN");
  }
  // dlsym also searches the library's dependencies: the symbol must be the plugin's own.
  link_map* own = nullptr;
  if (dlinfo(lib.native(), RTLD_DI_LINKMAP, &own) != 0 || own == nullptr || info.dli_fname == nullptr ||
      std::string(info.dli_fname) != own->l_name) {
    refuse(path, std::string(name) + " comes from " + (info.dli_fname ? info.dli_fname : "another library") +
                     ", a library this one depends on, not from the plugin itself");
  }
  void* function = *static_cast<void* const*>(symbol);
  Dl_info target{};
  if (function == nullptr || dladdr(function, &target) == 0 || target.dli_fbase != info.dli_fbase) {
    refuse(path, std::string(name) + " does not point to a function of this library");
  }
  return reinterpret_cast<Fn*>(function);
}

// A node made by a plugin: the library is destroyed after the node (members are destroyed in
// reverse order), and every value the node outputs keeps the library too.
class PluginNode final : public Node {
 public:
  PluginNode(std::shared_ptr<const void> library, std::unique_ptr<Node> inner)
      : library_(std::move(library)), inner_(std::move(inner)) {}

  void run(RunContext& ctx) const override {
    KeepAlive wrapped(ctx, library_);
    inner_->run(wrapped);
  }

 private:
  class KeepAlive final : public RunContext {
   public:
    KeepAlive(RunContext& base, const std::shared_ptr<const void>& library)
        : base_(base), library_(library) {}
    const std::string& node_id() const override { return base_.node_id(); }
    const Params& params() const override { return base_.params(); }
    const Value& input_value(const std::string& port) const override { return base_.input_value(port); }
    void set_output(const std::string& port, Value value) override {
      base_.set_output(port, value.empty() ? std::move(value) : value.kept_alive_by(library_));
    }
    void report(const std::string& key, Figure value) override { base_.report(key, std::move(value)); }
    void log(const std::string& message) override { base_.log(message); }
    bool reproducible() const override { return base_.reproducible(); }
    std::shared_ptr<const void> find_extension(const std::string& interface,
                                               const std::string& name) const override {
      return base_.find_extension(interface, name);
    }

   private:
    RunContext& base_;
    const std::shared_ptr<const void>& library_;
  };

  std::shared_ptr<const void> library_;
  std::unique_ptr<Node> inner_;
};

struct FactoryHolder {
  std::shared_ptr<const void> library;  // declared first: destroyed after the factories
  NodeFactory create;
  RegistryNodeFactory create_with_registry;
};

NodeType wrap_node_type(NodeType type, const std::shared_ptr<const void>& library) {
  auto holder = std::make_shared<const FactoryHolder>(
      FactoryHolder{library, std::move(type.create), std::move(type.create_with_registry)});
  auto wrapped = [holder](std::unique_ptr<Node> inner) -> std::unique_ptr<Node> {
    if (!inner) throw std::runtime_error("the plugin's factory returned no node");
    return std::make_unique<PluginNode>(holder->library, std::move(inner));
  };
  if (holder->create_with_registry) {
    type.create_with_registry = [holder, wrapped](const Params& params, const Registry& registry) {
      return wrapped(holder->create_with_registry(params, registry));
    };
  } else {
    type.create = [holder, wrapped](const Params& params) { return wrapped(holder->create(params)); };
  }
  return type;
}

// Everything that can be checked without touching the registry; throws on the first problem.
void check_record(const PluginRecord& record, const Registry& registry, const fs::path& path) {
  if (record.id.empty()) refuse(path, "the plugin record has an empty id");
  std::set<std::string> names;
  for (const NodeType& type : record.nodes) {
    if (type.spec.type.empty())
      refuse(path, "plugin " + record.id + " declares a node type with an empty name");
    if (!type.create && !type.create_with_registry)
      refuse(path, "node type " + type.spec.type + " has no factory");
    if (!names.insert(type.spec.type).second) {
      refuse(path, "node type " + type.spec.type + " is listed twice by plugin " + record.id);
    }
    if (registry.find_node(type.spec.type) != nullptr) {
      refuse(path, "node type " + type.spec.type + " already registered by " +
                       registry.node_origin(type.spec.type));
    }
  }
  std::set<std::pair<std::string, std::string>> extensions;
  for (const Extension& e : record.extensions) {
    const std::string what = "extension " + e.interface() + " '" + e.name() + "'";
    if (e.interface().empty() || e.name().empty()) refuse(path, what + " needs an interface and a name");
    if (e.empty()) refuse(path, what + " has no factory");
    if (!extensions.insert({e.interface(), e.name()}).second)
      refuse(path, what + " is listed twice by plugin " + record.id);
    if (registry.find_extension(e.interface(), e.name())) refuse(path, what + " is already registered");
  }
  // Whatever else the registry checks about a spec, on a scratch registry first.
  Registry scratch;
  try {
    for (const NodeType& type : record.nodes) scratch.add_node(type, {}, path.string());
    for (const Extension& e : record.extensions) scratch.add_extension(e, {}, path.string());
  } catch (const std::exception& e) {
    refuse(path, e.what());
  }
}

fs::path normalised(const fs::path& path) {
  std::error_code ec;
  fs::path absolute = fs::absolute(path, ec);
  if (ec) return path;
  fs::path canonical = fs::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal() : canonical;
}

}  // namespace

LoadedPlugin PluginLoader::load_file(const fs::path& library_path) {
  const fs::path path = normalised(library_path);
  for (const LoadedPlugin& plugin : loaded_) {
    if (plugin.path == path) return plugin;
  }
  std::error_code fs_ec;
  if (!fs::exists(path, fs_ec)) refuse(path, "no such file");
  if (fs::is_directory(path, fs_ec)) refuse(path, "is a directory, not a library");

  auto library = std::make_shared<Library>();
  {
    boost::dll::fs::error_code ec;
    dlerror();  // clear a stale message
    library->load(boost::dll::fs::path(path.string()), ec,
                  boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local |
                      static_cast<boost::dll::load_mode::type>(kExtraLoadFlags));
    if (ec || !library->is_loaded()) {
      const char* why = dlerror();
      refuse(path, std::string("not a loadable library: ") + (why ? why : ec.message()));
    }
  }

  const std::uint32_t abi = alias_function<PluginAbiVersionFn>(*library, kPluginAbiSymbol, path)();
  if (abi != kPluginAbiVersion) {
    refuse(path, "ABI version " + std::to_string(abi) + ", this host needs " +
                     std::to_string(kPluginAbiVersion) +
                     " (rebuild the plugin against this version of kg/graph/plugin_abi.hpp)");
  }
  PluginEntryFn* entry = alias_function<PluginEntryFn>(*library, kPluginEntrySymbol, path);

  LoadedPlugin result;
  {
    // The record holds code of the library: it must be gone before `library` may unload.
    PluginRecord record;
    try {
      record = entry();
    } catch (const std::exception& e) {
      refuse(path, std::string("entry threw: ") + e.what());
    } catch (...) {
      refuse(path, "entry threw an exception that is not a std::exception");
    }
    for (const LoadedPlugin& plugin : loaded_) {
      if (plugin.id == record.id) return plugin;  // the first one loaded wins
    }
    check_record(record, registry_, path);

    const std::shared_ptr<const void> owner = library;
    const std::string origin = path.string();
    for (NodeType& type : record.nodes)
      registry_.add_node(wrap_node_type(std::move(type), owner), owner, origin);
    for (Extension& e : record.extensions) registry_.add_extension(e.kept_alive_by(owner), owner, origin);
    result = LoadedPlugin{record.id, record.version, path, record.nodes.size(), record.extensions.size()};
  }
  loaded_.push_back(result);
  return result;
}

std::vector<std::string> PluginLoader::load_directory(const fs::path& dir) {
  std::vector<std::string> problems;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    problems.push_back(dir.string() + ": plugin directory not found");
    return problems;
  }
  std::vector<fs::path> libraries;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_ec;
    if (it->path().extension() == ".so" && it->is_regular_file(type_ec)) libraries.push_back(it->path());
  }
  if (ec) problems.push_back(dir.string() + ": cannot list the plugin directory: " + ec.message());
  std::sort(libraries.begin(), libraries.end());
  for (const fs::path& file : libraries) {
    try {
      const fs::path path = normalised(file);
      LoadedPlugin plugin = load_file(path);
      if (plugin.path != path) {
        problems.push_back(path.string() + ": skipped: plugin " + plugin.id + " is already loaded from " +
                           plugin.path.string());
      }
    } catch (const std::exception& e) {
      problems.push_back(e.what());
    }
  }
  return problems;
}

// An entry naming a path (it contains '/' or ends in ".so") is taken relative to the graph's
// directory; a bare name N is looked for as N.so, then N, in each search directory in order.
fs::path PluginLoader::resolve(const std::string& entry, const fs::path& graph_dir,
                               const std::vector<fs::path>& search_dirs) {
  if (entry.empty()) throw Error("empty plugin entry");
  std::error_code ec;
  const bool is_path = entry.find('/') != std::string::npos || fs::path(entry).extension() == ".so";
  if (is_path) {
    fs::path candidate = fs::path(entry).is_absolute() ? fs::path(entry) : graph_dir / entry;
    if (fs::exists(candidate, ec)) return normalised(candidate);
    throw Error("plugin " + text::in_quotes(entry) + " not found: no file or directory " +
                candidate.lexically_normal().string());
  }
  std::vector<std::string> looked;
  for (const fs::path& dir : search_dirs) {
    for (const fs::path& candidate : {dir / (entry + ".so"), dir / entry}) {
      if (fs::is_regular_file(candidate, ec)) return normalised(candidate);
      looked.push_back(candidate.string());
    }
  }
  std::ostringstream message;
  message << "plugin '" << entry << "' not found; looked for";
  if (looked.empty()) message << " it in no directory (no plugin directory given)";
  for (std::size_t i = 0; i < looked.size(); ++i) message << (i ? ", " : " ") << looked[i];
  throw Error(message.str());
}

std::vector<fs::path> plugin_path_from_environment() {
  std::vector<fs::path> dirs;
  const char* value = std::getenv("KINEGRAPH_PLUGIN_PATH");
  if (value == nullptr) return dirs;
  std::string text(value);
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find(':', start);
    if (end == std::string::npos) end = text.size();
    if (end > start) dirs.emplace_back(text.substr(start, end - start));
    start = end + 1;
  }
  return dirs;
}

}  // namespace kg::graph
