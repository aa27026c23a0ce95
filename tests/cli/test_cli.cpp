// The kinegraph CLI, run as a subprocess (KG_BINARY_DIR/bin/kinegraph) on graphs written to temp
// directories, with the test nodes (kg_test_nodes.so) from --plugin-dir KG_TEST_PLUGIN_DIR:
// exit codes, messages on stderr with file:line, --report JSON, nodes --json, dot, --set.
// The CLI loads the built-in node module (lib/kinegraph/kg_builtin_nodes.so) first; it must be
// built for these tests to pass (test_cli depends on it).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/process.hpp"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using kg::test::read_file;
using kg::test::Result;
using kg::test::run_program;
using kg::test::show;
using kg::test::TempDir;

const fs::path kKinegraph = fs::path(KG_BINARY_DIR) / "bin" / "kinegraph";
const fs::path kTestPlugins = KG_TEST_PLUGIN_DIR;
const fs::path kBadPlugins = fs::path(KG_TEST_PLUGIN_DIR) / "bad";

using kg::test::kinegraph;

// constant a (2) and constant b (${b}) -> add -> print to ${out}; line numbers matter below.
const char* kSumGraph =
    "version: 1\n"                                               // 1
    "doc: Adds two numbers and writes the sum.\n"                // 2
    "variables:\n"                                               // 3
    "  b: {doc: \"the second term\", default: \"3\"}\n"          // 4
    "  out: {doc: \"where the sum goes\", required: true}\n"     // 5
    "nodes:\n"                                                   // 6
    "  a: {type: test.constant, params: {value: 2}}\n"           // 7
    "  b: {type: test.constant, params: {value: \"${b}\"}}\n"    // 8
    "  sum: {type: test.add}\n"                                  // 9
    "  print: {type: test.print, params: {path: \"${out}\"}}\n"  // 10
    "connections:\n"                                             // 11
    "  - {from: a.value, to: sum.a}\n"                           // 12
    "  - {from: b.value, to: sum.b}\n"                           // 13
    "  - {from: sum.sum, to: print.value}\n";                    // 14

// A failing node with a downstream node, and an independent branch that must still run.
const char* kFailGraph =
    "version: 1\n"                                                         // 1
    "variables:\n"                                                         // 2
    "  out: {required: true}\n"                                            // 3
    "nodes:\n"                                                             // 4
    "  broken: {type: test.fail, params: {message: \"no luck today\"}}\n"  // 5
    "  after: {type: test.add}\n"                                          // 6
    "  fine: {type: test.constant, params: {value: 7}}\n"                  // 7
    "  print: {type: test.print, params: {path: \"${out}\"}}\n"            // 8
    "connections:\n"                                                       // 9
    "  - {from: broken.value, to: after.a}\n"                              // 10
    "  - {from: fine.value, to: print.value}\n";                           // 11

std::vector<std::string> with_plugins(std::vector<std::string> args) {
  args.push_back("--plugin-dir");
  args.push_back(kTestPlugins.string());
  return args;
}

}  // namespace

TEST_CASE("the CLI and its built-in node module are built", "[cli]") {
  REQUIRE(fs::exists(kKinegraph));
  CHECK(fs::exists(fs::path(KG_BINARY_DIR) / "lib" / "kinegraph" / "kg_builtin_nodes.so"));
  CHECK(fs::exists(kTestPlugins / "kg_test_nodes.so"));
}

TEST_CASE("--help and --version", "[cli]") {
  for (const char* flag : {"--help", "-h"}) {
    const Result r = kinegraph({flag});
    INFO(show(r));
    CHECK(r.code == 0);
    for (const char* text : {"usage:", "kinegraph run GRAPH", "validate", "nodes [--json]", "dot GRAPH",
                             "--set NAME=VALUE", "--jobs N", "--report FILE", "--plugin-dir DIR",
                             "KINEGRAPH_PLUGIN_PATH", "exit codes:", "2  usage error", "4  plugin error"}) {
      CHECK_THAT(r.out, Contains(text));
    }
    CHECK(r.err.empty());
  }
  CHECK(kinegraph({"run", "--help"}).code == 0);  // help wins wherever it is
  const Result v = kinegraph({"--version"});
  CHECK(v.code == 0);
  CHECK_THAT(v.out, StartsWith("kinegraph ") && Contains("plugin ABI 5"));
}

TEST_CASE("usage errors exit 2 with a message on stderr", "[cli]") {
  struct Case {
    std::vector<std::string> args;
    const char* message;
  };
  const Case cases[] = {
      {{}, "no verb given"},
      {{"rnu", "g.yaml"}, "unknown verb 'rnu'; did you mean 'run'?"},
      {{"run", "g.yaml", "--frobnicate"}, "unknown option '--frobnicate'"},
      {{"run"}, "run needs a GRAPH file"},
      {{"run", "a.yaml", "b.yaml"}, "unexpected argument 'b.yaml'"},
      {{"run", "g.yaml", "--jobs", "0"}, "--jobs expects a whole number from 1 to 1024, got '0'"},
      {{"run", "g.yaml", "--jobs=two"}, "got 'two'"},
      {{"run", "g.yaml", "--jobs"}, "--jobs needs a value"},
      {{"run", "g.yaml", "--set", "novalue"}, "--set expects NAME=VALUE, got 'novalue'"},
      {{"run", "g.yaml", "--set", "a=1", "--set", "a=2"}, "--set a is given twice"},
      {{"validate", "g.yaml", "--report", "r.json"}, "--report does not apply to validate"},
      {{"nodes", "--set", "a=1"}, "--set does not apply to nodes"},
      {{"run", "g.yaml", "--json"}, "--json does not apply to run"},
      {{"nodes", "extra"}, "unexpected argument 'extra'"},
  };
  for (const Case& c : cases) {
    const Result r = kinegraph(c.args);
    INFO(show(r));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, StartsWith("kinegraph: ") && Contains(c.message) && Contains("kinegraph --help"));
    CHECK(r.out.empty());
  }
}

TEST_CASE("a verb's --help lists its operand and the options that apply to it", "[cli]") {
  const Result run = kinegraph({"run", "--help"});
  INFO(show(run));
  CHECK(run.code == 0);
  CHECK_THAT(run.out, Contains("Usage: kinegraph run GRAPH") && Contains("--report FILE") &&
                          Contains("-j,--jobs N") && Contains("kinegraph --help"));
  CHECK_THAT(run.out, !Contains("--inputs"));
  const Result validate = kinegraph({"validate", "-h"});
  CHECK(validate.code == 0);
  CHECK_THAT(validate.out, Contains("--set NAME=VALUE") && !Contains("--report"));
  const Result merge = kinegraph({"merge", "--help"});
  CHECK_THAT(merge.out, Contains("Usage: kinegraph merge DIR") && !Contains("--plugin-dir"));
  CHECK(kinegraph({"help"}).out == kinegraph({"--help"}).out);  // the whole usage text
}

TEST_CASE("the forms of an option's value: attached, empty, and a flag given one", "[cli]") {
  struct Case {
    std::vector<std::string> args;
    const char* message;
  };
  const Case cases[] = {
      {{"run", "g.yaml", "--report="}, "--report needs a file name"},
      {{"run", "g.yaml", "--report=", "r.json"}, "--report needs a file name"},  // "" is the value
      {{"run", "g.yaml", "--set="}, "--set expects NAME=VALUE, got ''"},
      {{"run", "g.yaml", "--reproducible=yes"}, "--reproducible takes no value"},
      {{"run", "g.yaml", "--reproducible=true"}, "--reproducible takes no value"},
      {{"nodes", "--json="}, "--json takes no value"},
      {{"run", "g.yaml", "--", "--json"}, "unexpected argument '--json'"},
      {{"g.yaml", "run"}, "unknown verb 'g.yaml'"},
  };
  for (const Case& c : cases) {
    const Result r = kinegraph(c.args);
    INFO(show(r));
    CHECK(r.code == 2);
    CHECK_THAT(r.err, StartsWith("kinegraph: ") && Contains(c.message));
  }
}

TEST_CASE("run: --set, outputs, a summary, --report JSON", "[cli]") {
  TempDir dir;
  const fs::path graph = dir.write("sum.yaml", kSumGraph);
  const fs::path out = dir / "out" / "sum.txt";
  const fs::path report = dir / "report.json";

  const Result r = kinegraph(with_plugins({"run", graph.string(), "--set", "out=" + out.string(), "--set",
                                           "b=40.5", "--report", report.string(), "--jobs", "2"}));
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK(read_file(out) == "42.5\n");
  CHECK_THAT(r.out, Contains("sum.yaml: 4 nodes ran in"));
  CHECK_THAT(r.err, Contains("print: wrote " + out.string()));  // a node's log line, prefixed with its id

  const YAML::Node json = YAML::LoadFile(report.string());
  CHECK(json["ok"].as<bool>());
  CHECK(json["wall_seconds"].as<double>() >= 0);
  REQUIRE(json["nodes"].size() == 4);
  for (const YAML::Node& node : json["nodes"]) {
    CHECK(node["status"].as<std::string>() == "ok");
    CHECK(node["wall_seconds"].as<double>() >= 0);
  }
  CHECK(json["nodes"][2]["id"].as<std::string>() == "sum");
  CHECK(json["nodes"][2]["type"].as<std::string>() == "test.add");
  CHECK(json["nodes"][2]["figures"]["sum"].as<double>() == 42.5);

  SECTION("the default of a variable") {
    const Result d = kinegraph(with_plugins({"run", graph.string(), "--set", "out=" + out.string()}));
    INFO(show(d));
    CHECK(d.code == 0);
    CHECK(read_file(out) == "5\n");
  }
  SECTION("--name=value forms and options before the verb") {
    const Result d = kinegraph({"--plugin-dir=" + kTestPlugins.string(), "run", graph.string(),
                                "--set=out=" + out.string(), "--jobs=3"});
    INFO(show(d));
    CHECK(d.code == 0);
  }
  SECTION("a report that cannot be written fails the run") {
    const Result d = kinegraph(with_plugins({"run", graph.string(), "--set", "out=" + out.string(),
                                             "--report", dir.path().string()}));  // a directory
    INFO(show(d));
    CHECK(d.code == 1);
    CHECK_THAT(d.err, Contains("cannot write the report"));
  }
}

TEST_CASE("run: a failing node exits 1, names its place, skips its downstream only", "[cli]") {
  TempDir dir;
  const fs::path graph = dir.write("fail.yaml", kFailGraph);
  const fs::path out = dir / "fine.txt";
  const fs::path report = dir / "report.json";
  const Result r = kinegraph(
      with_plugins({"run", graph.string(), "--set", "out=" + out.string(), "--report", report.string()}));
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Contains("run failed: 1 of 4 nodes failed, 1 skipped"));
  CHECK_THAT(r.err,
             Contains(graph.string() + ":5") && Contains("node broken (test.fail) failed: no luck today"));
  CHECK_THAT(r.err, Contains("skipped: after"));
  CHECK(read_file(out) == "7\n");  // the independent branch ran

  const YAML::Node json = YAML::LoadFile(report.string());  // written for failed runs too
  CHECK_FALSE(json["ok"].as<bool>());
  std::map<std::string, std::string> status;
  for (const YAML::Node& node : json["nodes"])
    status[node["id"].as<std::string>()] = node["status"].as<std::string>();
  CHECK(status == std::map<std::string, std::string>{
                      {"broken", "failed"}, {"after", "skipped"}, {"fine", "ok"}, {"print", "ok"}});
}

TEST_CASE("run --jobs: independent branches really run in parallel", "[cli]") {
  TempDir dir;
  const fs::path graph =
      dir.write("meet.yaml",
                "version: 1\n"
                "variables:\n"
                "  timeout: {default: \"10\"}\n"
                "nodes:\n"
                "  left: {type: test.rendezvous, params: {timeout_seconds: \"${timeout}\"}}\n"
                "  right: {type: test.rendezvous, params: {timeout_seconds: \"${timeout}\"}}\n");
  const Result two = kinegraph(with_plugins({"run", graph.string(), "--jobs", "2"}));
  INFO(show(two));
  CHECK(two.code == 0);
  const Result one = kinegraph(with_plugins({"run", graph.string(), "--jobs", "1", "--set", "timeout=0.2"}));
  INFO(show(one));
  CHECK(one.code == 1);
  CHECK_THAT(one.err, Contains("timed out"));
}

TEST_CASE("invalid graphs exit 3 with file:line", "[cli]") {
  TempDir dir;
  struct Case {
    const char* name;
    std::string text;
    std::vector<std::string> extra;
    std::string message;  // after "<graph>:"
  };
  std::string sum = kSumGraph;
  const Case cases[] = {
      {"unknown type", "version: 1\nnodes:\n  a: {type: test.constnat}\n", {}, "3:"},
      {"unknown port",
       "version: 1\nnodes:\n  a: {type: test.constant}\n  p: {type: test.print, params: {path: x}}\n"
       "connections:\n  - {from: a.value, to: p.missing}\n",
       {},
       "6:"},
      {"param out of range",
       "version: 1\nnodes:\n  a: {type: test.constant, params: {value: 1e9}}\n",
       {},
       "3:"},
      {"unsupported version", "version: 7\nnodes:\n  a: {type: test.constant}\n", {}, "1:"},
      {"undeclared --set", sum, {"--set", "out=x", "--set", "nosuch=1"}, ""},
      {"not YAML", "version: 1\nnodes: [unclosed\n", {}, ""},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      const fs::path graph = dir.write("bad.yaml", c.text);
      std::vector<std::string> args{"validate", graph.string()};
      args.insert(args.end(), c.extra.begin(), c.extra.end());
      const Result r = kinegraph(with_plugins(args));
      INFO(show(r));
      CHECK(r.code == 3);
      CHECK_THAT(r.err, StartsWith("kinegraph: " + graph.string() + ":" + c.message));
      CHECK(r.out.empty());
      // run refuses it the same way, before anything runs
      args[0] = "run";
      CHECK(kinegraph(with_plugins(args)).code == 3);
    }
  }
  SECTION("the nearest node type name is suggested") {
    const fs::path graph = dir.write("typo.yaml", "version: 1\nnodes:\n  a: {type: test.constnat}\n");
    const Result r = kinegraph(with_plugins({"validate", graph.string()}));
    CHECK_THAT(r.err, Contains("test.constnat") && Contains("test.constant"));
  }
  SECTION("a missing graph file") {
    const Result r = kinegraph(with_plugins({"run", (dir / "absent.yaml").string()}));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Contains("absent.yaml: no such graph file"));
  }
  SECTION("without the plugin its node types are unknown") {
    const fs::path graph = dir.write("sum.yaml", kSumGraph);
    const Result r = kinegraph({"validate", graph.string(), "--set", "out=x"});
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Contains("sum.yaml:7:") && Contains("test.constant"));
  }
}

TEST_CASE("validate reports every problem, the values a run needs, and missing inputs", "[cli]") {
  TempDir dir;
  SECTION("a graph given no value for a required variable is valid, and says what a run needs") {
    const fs::path graph = dir.write("sum.yaml", kSumGraph);
    const Result v = kinegraph(with_plugins({"validate", graph.string()}));
    INFO(show(v));
    CHECK(v.code == 0);
    CHECK_THAT(v.out, Contains("sum.yaml: valid: 4 nodes, 3 connections") &&
                          Contains("a run needs: --set out=...") && Contains("out: where the sum goes"));
    const Result r = kinegraph(with_plugins({"run", graph.string()}));
    CHECK(r.code == 3);  // run still refuses it
    CHECK_THAT(r.err, Contains("variable 'out' is required and has no value"));
  }
  SECTION("the problems of the values given are still found") {
    const fs::path graph = dir.write("sum.yaml", kSumGraph);
    const Result v = kinegraph(with_plugins({"validate", graph.string(), "--set", "b=three"}));
    INFO(show(v));
    CHECK(v.code == 3);
    CHECK_THAT(v.err, Contains("sum.yaml:8:") && Contains("three"));
  }
  SECTION("three problems in three places, each with its line") {
    const fs::path graph = dir.write("bad.yaml",
                                     "version: 1\n"                                      // 1
                                     "nodes:\n"                                          // 2
                                     "  a: {type: test.constant, params: {value: x}}\n"  // 3
                                     "  b: {type: test.constnat}\n"                      // 4
                                     "  c: {type: test.constant, params: {valeu: 1}}\n"  // 5
                                     "  sum: {type: test.add}\n"                         // 6
                                     "connections:\n"                                    // 7
                                     "  - {from: a.value, to: sum.a}\n"                  // 8
                                     "  - {from: b.value, to: sum.b}\n"                  // 9
                                     "  - {from: c.nosuch, to: sum.b}\n");               // 10
    const Result v = kinegraph(with_plugins({"validate", graph.string()}));
    INFO(show(v));
    CHECK(v.code == 3);
    CHECK_THAT(v.err, Contains("bad.yaml:3:") && Contains("bad.yaml:4:") && Contains("bad.yaml:5:") &&
                          Contains("bad.yaml:10:") && Contains("invalid: 4 problems"));
    CHECK_THAT(v.err, !Contains("bad.yaml:9:"));  // b's type is unknown: its connection is not judged
    CHECK(v.out.empty());
    const Result r = kinegraph(with_plugins({"run", graph.string()}));
    CHECK(r.code == 3);  // run stops at the first
    CHECK_THAT(r.err, Contains("bad.yaml:3:") && !Contains("bad.yaml:4:"));
  }
  SECTION("an input path given must exist, unless the graph writes it") {
    const fs::path graph = dir.write("copy.yaml",
                                     "version: 1\n"
                                     "variables:\n"
                                     "  input: {required: true}\n"
                                     "nodes:\n"
                                     "  read: {type: test.read_number, params: {path: \"${input}\"}}\n");
    const Result absent =
        kinegraph(with_plugins({"validate", graph.string(), "--set", "input=/nonexistent.bvh"}));
    INFO(show(absent));
    CHECK(absent.code == 3);
    CHECK_THAT(absent.err, Contains("copy.yaml:5:") && Contains("'/nonexistent.bvh', which does not exist"));
    const fs::path present = dir.write("present.txt", "1");
    CHECK(kinegraph(with_plugins({"validate", graph.string(), "--set", "input=" + present.string()})).code ==
          0);
    const Result unknown = kinegraph(with_plugins({"validate", graph.string()}));
    CHECK(unknown.code == 0);
    CHECK_THAT(unknown.out, Contains("a run needs: --set input=..."));
  }
}

TEST_CASE("validate and dot", "[cli]") {
  TempDir dir;
  const fs::path graph = dir.write("sum.yaml", kSumGraph);
  const Result v = kinegraph(with_plugins({"validate", graph.string(), "--set", "out=x.txt"}));
  INFO(show(v));
  CHECK(v.code == 0);
  CHECK_THAT(v.out, Contains("sum.yaml: valid: 4 nodes, 3 connections"));
  CHECK_FALSE(fs::exists("x.txt"));  // validate runs nothing

  const Result d = kinegraph(with_plugins({"dot", graph.string(), "--set", "out=x.txt"}));
  INFO(show(d));
  CHECK(d.code == 0);
  CHECK_THAT(d.out, StartsWith("digraph \"sum.yaml\" {"));
  CHECK_THAT(d.out, Contains("\"sum\" [label=\"{{<i_a> a|<i_b> b?}|sum\\ntest.add|{<o_sum> sum}}\"];"));
  CHECK_THAT(d.out, Contains("\"a\":\"o_value\":e -> \"sum\":\"i_a\":w [label=\"kg.Scalar\""));
  CHECK_THAT(d.out, Contains("\"sum\":\"o_sum\":e -> \"print\":\"i_value\":w [label=\"kg.Scalar\""));
  CHECK(d.out.back() == '\n');
  CHECK(d.out.substr(d.out.size() - 2) == "}\n");
}

TEST_CASE("nodes: text and --json", "[cli]") {
  const std::string origin = fs::canonical(kTestPlugins / "kg_test_nodes.so").string();
  const Result t = kinegraph(with_plugins({"nodes"}));
  INFO(show(t));
  REQUIRE(t.code == 0);
  CHECK_THAT(t.out, Contains("test.add  (version 1, " + origin + ")"));
  CHECK_THAT(t.out, Contains("    b: kg.Scalar (optional)"));
  CHECK_THAT(t.out, Contains("    count: int = 2, in [1, inf]"));
  CHECK_THAT(t.out, Contains("    path: output_path, required"));

  const Result j = kinegraph(with_plugins({"nodes", "--json"}));
  INFO(show(j));
  REQUIRE(j.code == 0);
  const YAML::Node json = YAML::Load(j.out);
  CHECK(json["plugin_abi"].as<int>() == 5);
  REQUIRE(json["plugins"].size() >= 2);
  CHECK(
      json["plugins"][0]["path"].as<std::string>() ==
      fs::canonical(fs::path(KG_BINARY_DIR) / "lib/kinegraph/kg_builtin_nodes.so").string());  // loaded first
  bool listed = false;
  for (const YAML::Node& p : json["plugins"]) {
    if (p["id"].as<std::string>() == "kg.test_nodes") {
      listed = true;
      CHECK(p["nodes"].as<int>() == 6);
    }
  }
  CHECK(listed);

  std::map<std::string, YAML::Node> types;
  for (const YAML::Node& n : json["nodes"]) types[n["type"].as<std::string>()] = n;
  REQUIRE(types.count("test.rendezvous"));
  const YAML::Node rendezvous = types["test.rendezvous"];
  CHECK(rendezvous["origin"].as<std::string>() == origin);
  CHECK(rendezvous["inputs"][0]["name"].as<std::string>() == "in");
  CHECK_FALSE(rendezvous["inputs"][0]["required"].as<bool>());
  CHECK(rendezvous["outputs"][0]["type"].as<std::string>() == "kg.Scalar");
  const YAML::Node count = rendezvous["params"][1];
  CHECK(count["name"].as<std::string>() == "count");
  CHECK(count["type"].as<std::string>() == "int");
  CHECK(count["default"].as<int>() == 2);
  CHECK(count["min"].as<double>() == 1);
  CHECK(count["max"].IsNull());
  const YAML::Node path = types["test.print"]["params"][0];
  CHECK(path["required"].as<bool>());
  CHECK(path["default"].IsNull());
  CHECK(types["test.fail"]["params"][0]["default"].as<std::string>() == "deliberate failure");

  // Types of the built-in module appear too (whatever it provides), each with its origin.
  for (const auto& [name, node] : types) CHECK_FALSE(node["origin"].as<std::string>().empty());
}

TEST_CASE("plugins: search order, bad plugins are warnings, graph entries", "[cli]") {
  TempDir dir;
  const fs::path graph = dir.write("sum.yaml", kSumGraph);
  const fs::path out = dir / "sum.txt";

  SECTION("a directory of bad plugins only warns; the host keeps running") {
    const Result r = kinegraph({"run", graph.string(), "--set", "out=" + out.string(), "--plugin-dir",
                                kTestPlugins.string(), "--plugin-dir", kBadPlugins.string()});
    INFO(show(r));
    CHECK(r.code == 0);
    CHECK(read_file(out) == "5\n");
    for (const char* message :
         {"ABI version 999, this host needs 5", "no kg_plugin_entry symbol", "entry threw",
          "no kg_plugin_abi_version symbol", "is not a Boost.DLL alias", "a library this one depends on",
          "node type test.constant already registered by"}) {
      CHECK_THAT(r.err, Contains("kinegraph: warning: ") && Contains(message));
    }
  }
  SECTION("--plugin-dir order matters: the first to register a name keeps it") {
    // kg_bad_clash.so now loads first and owns test.constant, so kg_test_nodes.so is refused
    // whole (a warning): test.constant is the clash plugin's, which takes no params.
    const Result r = kinegraph({"validate", graph.string(), "--set", "out=" + out.string(), "--plugin-dir",
                                kBadPlugins.string(), "--plugin-dir", kTestPlugins.string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Contains("kg_test_nodes.so: node type test.constant already registered by"));
    CHECK_THAT(r.err,
               Contains("sum.yaml:7:") && Contains("unknown param 'value' for node 'a' (test.constant)"));
  }
  SECTION("a missing plugin directory only warns") {
    const Result r = kinegraph(with_plugins({"nodes", "--plugin-dir", (dir / "nowhere").string()}));
    CHECK(r.code == 0);
    CHECK_THAT(r.err, Contains("warning: ") && Contains("nowhere: plugin directory not found"));
  }
  SECTION("KINEGRAPH_PLUGIN_PATH") {
    const Result r =
        kinegraph({"run", graph.string(), "--set", "out=" + out.string()},
                  {"KINEGRAPH_PLUGIN_PATH=" + (dir / "nowhere").string() + ":" + kTestPlugins.string()});
    INFO(show(r));
    CHECK(r.code == 0);
    CHECK_THAT(r.err, Contains("nowhere: plugin directory not found (from KINEGRAPH_PLUGIN_PATH)"));
  }
  SECTION("the graph's plugins: a path relative to the graph") {
    fs::create_directories(dir / "mine");
    fs::copy_file(kTestPlugins / "kg_test_nodes.so", dir / "mine" / "nodes.so");
    std::string text = kSumGraph;
    text.insert(text.find("nodes:\n"), "plugins: [mine/nodes.so]\n");
    const fs::path g = dir.write("with_plugin.yaml", text);
    const Result r = kinegraph({"run", g.string(), "--set", "out=" + out.string()});
    INFO(show(r));
    CHECK(r.code == 0);
    CHECK(read_file(out) == "5\n");
  }
  SECTION("the graph's plugins: a directory, named through a variable") {
    std::string text = kSumGraph;
    text.insert(text.find("nodes:\n"), "plugins: [\"${plugins}\"]\n");
    text.insert(text.find("  out:"), "  plugins: {doc: \"a plugin directory\", required: true}\n");
    const fs::path g = dir.write("with_dir.yaml", text);
    const Result r = kinegraph(
        {"run", g.string(), "--set", "out=" + out.string(), "--set", "plugins=" + kTestPlugins.string()});
    INFO(show(r));
    CHECK(r.code == 0);
  }
  SECTION("the graph's plugins: a bare name from the default plugin directory") {
    if (!fs::exists(fs::path(KG_PLUGIN_DIR) / "kg_lowpass.so")) {
      WARN("skipped: kg_lowpass.so not built");
      return;
    }
    // filter.lowpass fed a kg.Scalar: the type error proves the plugin's node type was found.
    const fs::path g = dir.write("lowpass.yaml",
                                 "version: 1\n"
                                 "plugins: [kg_lowpass]\n"
                                 "nodes:\n"
                                 "  a: {type: test.constant}\n"
                                 "  smooth: {type: filter.lowpass}\n"
                                 "connections:\n"
                                 "  - {from: a.value, to: smooth.motion}\n");
    const Result r = kinegraph(with_plugins({"validate", g.string()}));
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Contains("lowpass.yaml:7:") && Contains("kg.Motion") && Contains("kg.Scalar"));
  }
  SECTION("a plugin the graph names but cannot be found: exit 4") {
    std::string text = kSumGraph;
    const std::size_t at = text.find("nodes:\n");
    text.insert(at, "plugins: [no_such_plugin]\n");
    const auto line = std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n') + 1;
    const fs::path g = dir.write("missing.yaml", text);
    const Result r = kinegraph(with_plugins({"run", g.string(), "--set", "out=" + out.string()}));
    INFO(show(r));
    CHECK(r.code == 4);
    // The entry's own line and column.
    CHECK_THAT(r.err, Contains("missing.yaml:" + std::to_string(line) +
                               ":11: plugins: plugin 'no_such_plugin' not found; "
                               "looked for " +
                               (kTestPlugins / "no_such_plugin.so").string()));
    CHECK_FALSE(fs::exists(out));
  }
  SECTION("a bad plugin the graph names: exit 4") {
    std::string text = kSumGraph;
    text.insert(text.find("nodes:\n"),
                "plugins: [\"" + (kBadPlugins / "kg_bad_abi_999.so").string() + "\"]\n");
    const fs::path g = dir.write("bad_plugin.yaml", text);
    const Result r = kinegraph(with_plugins({"run", g.string(), "--set", "out=" + out.string()}));
    INFO(show(r));
    CHECK(r.code == 4);
    CHECK_THAT(r.err, Contains("ABI version 999, this host needs 5"));
  }
}

TEST_CASE("a missing built-in node module is a plugin error (exit 4)", "[cli]") {
  // A copy of the CLI in a prefix without lib/kinegraph/ (it still finds libkg_graph through
  // its build-tree run path).
  TempDir dir;
  fs::create_directories(dir / "bin");
  fs::copy_file(kKinegraph, dir / "bin" / "kinegraph");
  const Result r = run_program(dir / "bin" / "kinegraph", {"nodes"});
  INFO(show(r));
  CHECK(r.code == 4);
  CHECK_THAT(
      r.err,
      Contains(
          "the built-in node module is missing: " +
          (dir / "bin" / ".." / "lib" / "kinegraph" / "kg_builtin_nodes.so").lexically_normal().string()));
  // --help needs no module
  CHECK(run_program(dir / "bin" / "kinegraph", {"--help"}).code == 0);
}

TEST_CASE("a bad option of a built-in node is refused at load with file:line, before anything runs",
          "[cli]") {
  TempDir dir;
  const fs::path out = dir.path() / "never.bvh";
  const std::string text =
      "version: 1\n"                                               // 1
      "nodes:\n"                                                   // 2
      "  walk: {type: motion.synthesize}\n"                        // 3
      "  holds: {type: retarget.holds, params: {points: \"\"}}\n"  // 4
      "  save: {type: io.export_bvh, params: {path: \"" +
      out.string() +
      "\"}}\n"                                        // 5
      "connections:\n"                                // 6
      "  - {from: walk.motion, to: holds.motion}\n"   // 7
      "  - {from: walk.motion, to: holds.motion2}\n"  // 8
      "  - {from: walk.motion, to: save.motion}\n";   // 9
  const fs::path graph = dir.write("bad_option.yaml", text);
  for (const char* verb : {"validate", "run"}) {
    const Result r = kinegraph({verb, graph.string()});
    INFO(verb << "\n" << show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, StartsWith("kinegraph: " + graph.string() + ":4:"));
    CHECK_THAT(r.err, Contains("node 'holds' (retarget.holds)") && Contains("HoldOptions.points_a = []") &&
                          Contains("expected at least one point"));
  }
  CHECK_FALSE(fs::exists(out));  // refused before any node ran
}

TEST_CASE("a fuzzed joint-name pattern fails at its file:line with a short excerpt, writing nothing",
          "[cli]") {
  // Fuzzing found these crashing the CLI (SIGSEGV in std::regex); they now go through RE2.
  TempDir dir;
  const fs::path source = KG_SOURCE_DIR;
  const fs::path clip = source / "tests/graphs/data/two_joints.bvh";
  const std::string deep(30000, '(');
  // Which line of stderr says `what` (none: "").
  const auto line_with = [](const std::string& text, const std::string& what) {
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
      if (line.find(what) != std::string::npos) return line;
    return std::string();
  };

  SECTION("a target file: the run fails at the pattern's key, no clip or report written") {
    // A key longer than YAML's 1024 characters is written explicitly: "? key", ": value".
    const fs::path target = dir.write("deep.yaml", "version: 1\nbones:\n  ? \"" + deep + "\"\n  : 0.5\n");
    const fs::path out = dir.path() / "out.bvh", report = dir.path() / "metrics.json";
    const Result r = kinegraph({"run", (source / "graphs/retarget.yaml").string(), "--set",
                                "input=" + clip.string(), "--set", "target=" + target.string(), "--set",
                                "output=" + out.string(), "--set", "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    const std::string line = line_with(r.err, "bad regular expression");
    CHECK_THAT(line,
               Contains(target.string() + ":3:5: bones: bad regular expression '" + std::string(60, '(') +
                        "'... (30000 bytes): longer than the 4096 bytes allowed"));
    CHECK(line.size() < 400 + target.string().size());
    CHECK(r.err.find(std::string(100, '(')) == std::string::npos);  // never quoted whole
    CHECK_FALSE(fs::exists(out));
    CHECK_FALSE(fs::exists(report));
  }

  SECTION("a freeze pattern given with --set: refused at load, at the node's line") {
    const fs::path out = dir.path() / "follow.bvh";
    const Result r = kinegraph({"validate", (source / "graphs/salsa.yaml").string(), "--set",
                                "follow=" + clip.string(), "--set", "lead=" + clip.string(), "--set",
                                "output=" + out.string(), "--set", "lead_fixed=" + deep});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, StartsWith("kinegraph: " + (source / "graphs/salsa.yaml").string() + ":"));
    const std::string line = line_with(r.err, "bad regular expression");
    CHECK_THAT(line, Contains("(retarget.spacetime): freeze2: bad regular expression '((((") &&
                         Contains("... (30000 bytes)"));
    CHECK(line.size() < 500);
    CHECK_FALSE(fs::exists(out));
  }
}

TEST_CASE("inspect: the motion doctor on a clip, as text and JSON, bad clips exit non-zero", "[cli]") {
  const fs::path clip = fs::path(KG_DATA_DIR) / "cmu/bvh_cmu_names/16_01.bvh";
  SECTION("16_01.bvh says 30 fps: its jump's flight says 120, and the fix is given") {
    if (!fs::exists(clip)) {
      WARN("skipped: " << clip << " not found");
      return;
    }
    const Result text = kinegraph({"inspect", clip.string()});
    INFO(show(text));
    REQUIRE(text.code == 0);
    CHECK_THAT(text.out, Contains("read: ") && Contains("322 frames at 30 fps") &&
                             Contains("the clip's true rate is 120 fps") && Contains("plants of lfoot: ") &&
                             Contains("flight frames ") && Contains("fixes: --set source_fps=120"));
    const Result json = kinegraph({"inspect", clip.string(), "--json"});
    INFO(show(json));
    REQUIRE(json.code == 0);
    const YAML::Node doc = YAML::Load(json.out);
    CHECK(doc["up"].as<std::string>() == "y");
    CHECK(doc["units"].as<std::string>() == "asf");
    CHECK(doc["header_fps"].as<double>() == 30.0);
    CHECK(doc["source_fps"].as<double>() == 120.0);
    CHECK(doc["calibration_frames"].size() == 0);
    CHECK(doc["plants"].size() == 4);
    REQUIRE(doc["flights"].size() >= 1);
    CHECK(doc["fixes"][0].as<std::string>() == "--set source_fps=120");
    // The fix applied: the rate is confirmed and nothing is left to fix.
    const Result fixed = kinegraph({"inspect", clip.string(), "--json", "--set", "source_fps=120"});
    REQUIRE(fixed.code == 0);
    CHECK(YAML::Load(fixed.out)["fixes"].size() == 0);
  }
  SECTION("no clip, a missing clip, a clip without feet") {
    CHECK(kinegraph({"inspect"}).code == 2);
    const Result missing = kinegraph({"inspect", "/nonexistent/walk.bvh"});
    CHECK(missing.code == 1);
    CHECK_THAT(missing.err, Contains("/nonexistent/walk.bvh") && Contains("no such BVH file"));
    const Result feet =
        kinegraph({"inspect", (fs::path(KG_SOURCE_DIR) / "tests/graphs/data/two_joints.bvh").string()});
    INFO(show(feet));
    CHECK(feet.code == 1);
    CHECK_THAT(feet.err, Contains("two_joints.bvh") && Contains("foot"));
    CHECK(kinegraph({"inspect", clip.string(), "--set", "input=x.bvh"}).code == 2);
  }
}

TEST_CASE("inspect: --set trim reads only those frames", "[cli]") {
  const fs::path clip = fs::path(KG_DATA_DIR) / "cmu/bvh_daz/13_11.bvh";
  if (!fs::exists(clip)) {
    WARN("skipped: " << clip << " not found");
    return;
  }
  const Result all = kinegraph({"inspect", clip.string(), "--json"});
  const Result cut = kinegraph({"inspect", clip.string(), "--json", "--set", "trim=5.."});
  INFO(show(all) << "\n" << show(cut));
  REQUIRE(all.code == 0);
  REQUIRE(cut.code == 0);
  CHECK(YAML::Load(all.out)["calibration_frames"].size() == 5);
  CHECK(YAML::Load(cut.out)["calibration_frames"].size() == 0);
  CHECK(YAML::Load(cut.out)["frames"].as<int>() == YAML::Load(all.out)["frames"].as<int>() - 5);
}

TEST_CASE("map: chains of a clip and a robot, matched and written, bad operands refused", "[cli]") {
  const fs::path clip = fs::path(KG_DATA_DIR) / "cmu/asf_amc/07_05.amc";
  const fs::path robot = fs::path(KG_DATA_DIR) / "robots/unitree_g1/g1_29dof.urdf";
  if (!fs::exists(clip) || !fs::exists(robot)) {
    WARN("skipped: " << clip << " or " << robot << " not found");
    return;
  }
  const TempDir dir;
  SECTION("07_05.amc onto the G1: every chain matched, the file names the robot's joints") {
    const fs::path out = dir.path() / "walk_to_g1.yaml";
    const Result r = kinegraph({"map", clip.string(), robot.string(), "--out", out.string()});
    INFO(show(r));
    REQUIRE(r.code == 0);
    CHECK_THAT(r.out,
               Contains("read: 07_05.amc: skeleton not given") &&
                   Contains("found: target: legs: left is left_hip_pitch_joint (by name)") &&
                   Contains("matched left_leg: lfemur, ltibia, lfoot, ltoes -> left_hip_pitch_joint") &&
                   Contains("unpaired: clavicle (only the source has one: lclavicle)") &&
                   Contains("26 feature pairs from 7 chains") && Contains("wrote " + out.string()));
    CHECK_THAT(r.out, !Contains("not matched"));
    const YAML::Node map = YAML::LoadFile(out.string());
    CHECK(map["version"].as<int>() == 1);
    CHECK(map["source"]["chains"]["pelvis"].as<std::string>() == "root");
    CHECK(map["target"]["chains"]["right_arm"]["wrist"].as<std::string>() == "right_wrist_roll_joint");
    CHECK(map["target"]["chains"]["spine"].size() == 3);
  }
  SECTION("without --out nothing is written; an .asf alone is a source") {
    const Result r = kinegraph({"map", (clip.parent_path() / "07.asf").string(), robot.string()});
    INFO(show(r));
    REQUIRE(r.code == 0);
    CHECK_THAT(r.out, Contains("an ASF skeleton alone") && Contains("(not written: give --out MAP.yaml"));
  }
  SECTION("a target without limbs: nothing matched, said, and a warning") {
    const Result r = kinegraph(
        {"map", clip.string(), (fs::path(KG_SOURCE_DIR) / "tests/graphs/data/two_joints.bvh").string()});
    INFO(show(r));
    REQUIRE(r.code == 0);
    CHECK_THAT(r.out, Contains("not matched: left_leg: only the source has it") &&
                          Contains("not matched: target: no pair of mirrored limbs") &&
                          Contains("0 feature pairs") && Contains("warning: no chain is on both skeletons"));
  }
  SECTION("usage and input errors") {
    CHECK(kinegraph({"map", clip.string()}).code == 2);
    const Result missing = kinegraph({"map", clip.string(), "/nonexistent/robot.urdf"});
    CHECK(missing.code == 1);
    CHECK_THAT(missing.err, Contains("/nonexistent/robot.urdf"));
    const Result not_yaml =
        kinegraph({"map", clip.string(), robot.string(), "--out", (dir.path() / "m.bvh").string()});
    CHECK(not_yaml.code == 3);
    CHECK_THAT(not_yaml.err, Contains("m.bvh: a skeleton map is written as YAML"));
    CHECK_FALSE(fs::exists(dir.path() / "m.bvh"));
  }
}
