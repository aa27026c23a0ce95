// PluginLoader against real libraries built by CMake: the test-nodes plugin, the deliberately bad
// plugins of tests/plugins/bad, and garbage written here. A refused plugin must leave the
// registry exactly as it was and usable.
#include <dlfcn.h>
#include <stdlib.h>

#include <catch2/catch.hpp>

#include "kg/base/error.hpp"
#include "kg/graph/plugin_abi.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/motion/nodes.hpp"
#include "plugin_test_util.hpp"

using namespace kg_test;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

std::string refusal(PluginLoader& loader, const fs::path& path) {
  try {
    loader.load_file(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "(loaded without error)";
}

// The registry and loader state that a refusal must leave untouched.
struct Snapshot {
  std::vector<std::string> nodes;
  std::size_t plugins;
  bool operator==(const Snapshot&) const = default;
};
Snapshot snapshot(const Registry& r, const PluginLoader& l) {
  return {r.node_type_names(), l.loaded().size()};
}

// After a refusal: loading a good plugin and running one of its nodes still works.
void check_usable(Registry& registry, PluginLoader& loader) {
  if (registry.find_node("test.add") == nullptr) loader.load_file(test_nodes_library());
  const NodeContext ctx =
      kg::test::run_node(registry, "test.add", Params{}, {{"a", Value::make(2.0)}, {"b", Value::make(3.5)}});
  CHECK(ctx.outputs.at("sum").get<double>() == 5.5);
}

}  // namespace

TEST_CASE("a good plugin loads: record, origin, nodes that run", "[plugins]") {
  Registry registry;
  PluginLoader loader(registry);
  const LoadedPlugin plugin = loader.load_file(test_nodes_library());
  CHECK(plugin.id == "kg.test_nodes");
  CHECK(plugin.version == "1.0.0");
  CHECK(plugin.path == fs::canonical(test_nodes_library()));
  CHECK(plugin.node_count == 6);
  CHECK(plugin.extension_count == 0);
  REQUIRE(loader.loaded().size() == 1);
  CHECK(registry.node_type_names() == std::vector<std::string>{"test.add", "test.constant", "test.fail",
                                                               "test.print", "test.read_number",
                                                               "test.rendezvous"});
  CHECK(registry.node_origin("test.add") == fs::canonical(test_nodes_library()).string());
  CHECK(registry.node_owner("test.add") != nullptr);
  check_usable(registry, loader);

  SECTION("loading the same file again is not an error and adds nothing") {
    const LoadedPlugin again = loader.load_file(test_nodes_library());
    CHECK(again.path == plugin.path);
    CHECK(loader.loaded().size() == 1);
  }
}

TEST_CASE("bad plugins are refused with a clear message, the registry unchanged", "[plugins]") {
  Registry registry;
  PluginLoader loader(registry);
  loader.load_file(test_nodes_library());
  const Snapshot before = snapshot(registry, loader);

  struct Case {
    const char* plugin;
    std::string message;
  };
  const Case cases[] = {
      {"abi_999", "ABI version 999, this host needs 5"},
      {"no_entry", "no kg_plugin_entry symbol: not a Kinegraph plugin"},
      {"no_abi", "no kg_plugin_abi_version symbol: not a Kinegraph plugin"},
      {"entry_throws", "entry threw: deliberately thrown by the entry"},
      {"clash",
       "node type test.constant already registered by " + fs::canonical(test_nodes_library()).string()},
      {"plain_symbol", "kg_plugin_abi_version is not a Boost.DLL alias"},
      {"borrowed", "kg_plugin_abi_version comes from " +
                       (fs::path(KG_TEST_PLUGIN_DIR) / "bad" / "deps" / "kg_bad_borrowed_base.so").string() +
                       ", a library this one depends on"},
  };
  for (const Case& c : cases) {
    SECTION(c.plugin) {
      const fs::path path = bad_plugin(c.plugin);
      REQUIRE(fs::exists(path));
      const std::string message = refusal(loader, path);
      CHECK_THAT(message, StartsWith(fs::canonical(path).string() + ": "));
      CHECK_THAT(message, Contains(c.message));
      CHECK(snapshot(registry, loader) == before);
      CHECK(registry.find_node("clash.unique") == nullptr);
      check_usable(registry, loader);
    }
  }
}

TEST_CASE("the clashing plugin loads where nothing clashes", "[plugins]") {
  // Proves that the clash case above was refused for the clash, not for being broken.
  Registry registry;
  PluginLoader loader(registry);
  CHECK(loader.load_file(bad_plugin("clash")).node_count == 2);
  CHECK(registry.find_node("clash.unique") != nullptr);
  // ... and that the clash is symmetric: now kg_test_nodes is the one refused, wholly.
  const std::string message = refusal(loader, test_nodes_library());
  CHECK_THAT(message, Contains("node type test.constant already registered by"));
  CHECK(registry.find_node("test.add") == nullptr);
}

TEST_CASE("the library kg_bad_borrowed depends on is a plugin in its own right", "[plugins]") {
  // So the refusal above is about where the symbols live, not about broken symbols.
  Registry registry;
  PluginLoader loader(registry);
  CHECK(loader.load_file(fs::path(KG_TEST_PLUGIN_DIR) / "bad" / "deps" / "kg_bad_borrowed_base.so").id ==
        "kg.test_borrowed_base");
}

TEST_CASE("files that are not libraries are refused", "[plugins]") {
  TempDir dir;
  Registry registry;
  PluginLoader loader(registry);

  SECTION("garbage named bad.so") {
    // Longer than an ELF header, so that dlopen reads and rejects the header itself.
    dir.write("bad.so", std::string(4096, 'x'));
    const std::string message = refusal(loader, dir / "bad.so");
    CHECK_THAT(message, StartsWith((dir / "bad.so").string() + ": not a loadable library: "));
    CHECK_THAT(message, Contains("invalid ELF header"));
  }
  SECTION("an empty file") {
    dir.write("empty.so", "");
    CHECK_THAT(refusal(loader, dir / "empty.so"), Contains("not a loadable library: "));
  }
  SECTION("a truncated copy of a real plugin") {
    std::ifstream in(test_nodes_library(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    dir.write("truncated.so", bytes.substr(0, 256));
    CHECK_THAT(refusal(loader, dir / "truncated.so"), Contains("not a loadable library: "));
  }
  SECTION("a missing file") {
    CHECK_THAT(refusal(loader, dir / "missing.so"), Contains("missing.so: no such file"));
  }
  SECTION("a directory") {
    fs::create_directories(dir / "sub.so");
    CHECK_THAT(refusal(loader, dir / "sub.so"), Contains("is a directory"));
  }
  CHECK(registry.node_type_names().empty());
  CHECK(loader.loaded().empty());
  check_usable(registry, loader);
}

TEST_CASE("load_directory: every *.so in name order, messages for the refused", "[plugins]") {
  Registry registry;
  PluginLoader loader(registry);

  SECTION("the bad plugins' directory: one message each, never a throw") {
    loader.load_file(test_nodes_library());
    const Snapshot before = snapshot(registry, loader);
    const std::vector<std::string> problems = loader.load_directory(fs::path(KG_TEST_PLUGIN_DIR) / "bad");
    REQUIRE(problems.size() == 7);
    // Name order: abi_999, borrowed, clash, entry_throws, no_abi, no_entry, plain_symbol.
    CHECK_THAT(problems[0], Contains("kg_bad_abi_999.so: ABI version 999"));
    CHECK_THAT(problems[1], Contains("kg_bad_borrowed.so: kg_plugin_abi_version comes from"));
    CHECK_THAT(problems[2], Contains("kg_bad_clash.so: node type test.constant already registered"));
    CHECK_THAT(problems[3], Contains("kg_bad_entry_throws.so: entry threw"));
    CHECK_THAT(problems[4], Contains("kg_bad_no_abi.so: no kg_plugin_abi_version symbol"));
    CHECK_THAT(problems[5], Contains("kg_bad_no_entry.so: no kg_plugin_entry symbol"));
    CHECK_THAT(problems[6],
               Contains("kg_bad_plain_symbol.so: kg_plugin_abi_version is not a Boost.DLL alias"));
    CHECK(snapshot(registry, loader) == before);
    check_usable(registry, loader);
  }

  SECTION("garbage beside a good plugin; other file names ignored") {
    TempDir dir;
    dir.write("bad.so", "garbage");
    dir.write("notes.txt", "not a plugin, not even looked at");
    dir.write("libsomething.so.1", "versioned names are not *.so");
    fs::copy_file(test_nodes_library(), dir / "nodes.so");
    const std::vector<std::string> problems = loader.load_directory(dir.path());
    REQUIRE(problems.size() == 1);
    CHECK_THAT(problems[0], Contains("bad.so: not a loadable library"));
    REQUIRE(loader.loaded().size() == 1);
    CHECK(loader.loaded()[0].path == fs::canonical(dir / "nodes.so"));
    check_usable(registry, loader);
  }

  SECTION("the same plugin id twice: the first in name order wins, the other is skipped") {
    TempDir dir;
    fs::copy_file(test_nodes_library(), dir / "b_copy.so");
    fs::copy_file(test_nodes_library(), dir / "a_copy.so");
    const std::vector<std::string> problems = loader.load_directory(dir.path());
    REQUIRE(problems.size() == 1);
    CHECK_THAT(problems[0], Contains("b_copy.so: skipped: plugin kg.test_nodes is already loaded from " +
                                     fs::canonical(dir / "a_copy.so").string()));
    REQUIRE(loader.loaded().size() == 1);
    CHECK(registry.node_origin("test.add") == fs::canonical(dir / "a_copy.so").string());
    // load_file returns the first one's record for another copy.
    CHECK(loader.load_file(dir / "b_copy.so").path == fs::canonical(dir / "a_copy.so"));
  }

  SECTION("a missing directory is one message") {
    TempDir dir;
    const std::vector<std::string> problems = loader.load_directory(dir / "nowhere");
    REQUIRE(problems.size() == 1);
    CHECK_THAT(problems[0], Contains("nowhere: plugin directory not found"));
  }
}

TEST_CASE("resolve: paths relative to the graph, bare names in the search directories", "[plugins]") {
  TempDir dir;
  fs::create_directories(dir / "graphs" / "local");
  fs::create_directories(dir / "first");
  fs::create_directories(dir / "second");
  dir.write("graphs/local/mine.so", "x");
  dir.write("second/kg_lowpass.so", "x");
  dir.write("first/other.so", "x");
  const fs::path graph_dir = dir / "graphs";
  const std::vector<fs::path> search = {dir / "first", dir / "second"};

  CHECK(PluginLoader::resolve("kg_lowpass", graph_dir, search) ==
        fs::canonical(dir / "second" / "kg_lowpass.so"));
  CHECK(PluginLoader::resolve("other", graph_dir, search) == fs::canonical(dir / "first" / "other.so"));
  CHECK(PluginLoader::resolve("local/mine.so", graph_dir, search) ==
        fs::canonical(dir / "graphs/local/mine.so"));
  // Without a '/' or ".so" an entry is a bare name, never looked for beside the graph.
  CHECK_THROWS_WITH(PluginLoader::resolve("local", graph_dir, {}), Contains("no plugin directory given"));
  CHECK(PluginLoader::resolve("./local", graph_dir, search) == fs::canonical(dir / "graphs/local"));
  CHECK(PluginLoader::resolve((dir / "first/other.so").string(), "/nowhere", {}) ==
        fs::canonical(dir / "first/other.so"));

  CHECK_THROWS_WITH(
      PluginLoader::resolve("absent", graph_dir, search),
      Contains("plugin 'absent' not found; looked for " + (dir / "first" / "absent.so").string()) &&
          Contains((dir / "second" / "absent").string()));
  CHECK_THROWS_WITH(
      PluginLoader::resolve("local/none.so", graph_dir, search),
      Contains("plugin 'local/none.so' not found") && Contains((graph_dir / "local/none.so").string()));
}

TEST_CASE("KINEGRAPH_PLUGIN_PATH is split on ':' skipping empty parts", "[plugins]") {
  const char* old = std::getenv("KINEGRAPH_PLUGIN_PATH");
  const std::string saved = old ? old : "";
  ::setenv("KINEGRAPH_PLUGIN_PATH", "/a/b::relative:/c:", 1);
  CHECK(plugin_path_from_environment() == std::vector<fs::path>{"/a/b", "relative", "/c"});
  ::unsetenv("KINEGRAPH_PLUGIN_PATH");
  CHECK(plugin_path_from_environment().empty());
  if (old) ::setenv("KINEGRAPH_PLUGIN_PATH", saved.c_str(), 1);
}

TEST_CASE("a plugin's library stays loaded while a node made from it lives", "[plugins]") {
  const std::string path = fs::canonical(test_nodes_library()).string();
  auto is_loaded = [&] {
    void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
    if (handle) ::dlclose(handle);
    return handle != nullptr;
  };
  NodePtr node;
  {
    Registry registry;
    PluginLoader loader(registry);
    loader.load_file(path);
    node = registry.create_node("test.constant", params_for(registry, "test.constant", {{"value", 4.25}}));
  }  // the registry and the loader are gone
  REQUIRE(is_loaded());
  Value out;
  {
    NodeContext ctx;
    node->run(ctx);
    out = ctx.outputs.at("value");
  }
  node.reset();
  CHECK(is_loaded());  // the value it made keeps the library too
  CHECK(out.get<double>() == 4.25);
}
