// Graph files: loading, variables, param coercion, and a table of invalid files, each of which
// must be refused with the right file:line:column and the names involved.
#include <catch2/catch.hpp>

#include "kg/graph/yaml_io.hpp"
#include "test_nodes.hpp"

using namespace kg;
using namespace kg::graph;

namespace {

const std::filesystem::path kData = std::filesystem::path(KG_SOURCE_DIR) / "tests" / "graph" / "data";

Graph load(const std::string& text, const std::map<std::string, std::string>& overrides = {}) {
  static const Registry registry = kg_test::test_registry();
  return load_graph_from_string(text, "t.yaml", registry, overrides);
}

std::string load_error(const std::string& text, const std::map<std::string, std::string>& overrides = {}) {
  try {
    load(text, overrides);
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT a kg::Error: ") + e.what();
  }
  return "NO ERROR";
}

const NodeInstance& node(const Graph& g, const std::string& id) {
  const NodeInstance* n = g.find_node(id);
  REQUIRE(n != nullptr);
  return *n;
}

}  // namespace

TEST_CASE("a valid graph loads: nodes in file order, defaults filled, connections kept") {
  const Graph g = load(R"(version: 1
doc: Adds two numbers and scales the sum.
nodes:
  sum: {type: test.add, doc: "a + b"}
  a: {type: test.constant, params: {value: 2}}
  b:
    type: test.constant
    params:
      value: 3.5
  twice: {type: test.scale, params: {factor: 2}}
connections:
  - {from: a.out, to: sum.a}
  - from: b.out
    to: sum.b
  - {from: sum.sum, to: twice.in}
)");
  CHECK(g.doc == "Adds two numbers and scales the sum.");
  CHECK(g.file == "t.yaml");
  REQUIRE(g.nodes.size() == 4);
  CHECK(g.nodes[0].id == "sum");
  CHECK(g.nodes[1].id == "a");
  CHECK(g.nodes[0].where.to_string() == "t.yaml:4:3");
  CHECK(g.nodes[2].where.to_string() == "t.yaml:6:3");
  CHECK(node(g, "a").params.get<double>("value") == 2.0);
  CHECK(node(g, "b").params.get<double>("value") == 3.5);
  CHECK(node(g, "twice").params.get<double>("factor") == 2.0);
  CHECK(node(g, "sum").params.all().empty());
  for (const NodeInstance& n : g.nodes) CHECK(n.node != nullptr);
  REQUIRE(g.connections.size() == 3);
  CHECK(g.connections[1].from.to_string() == "b.out");
  CHECK(g.connections[1].to.to_string() == "sum.b");
  CHECK(g.connections[1].where.to_string() == "t.yaml:13:5");
  // a and b first (file order among ready nodes), then sum, then twice.
  CHECK(g.topological_order() == std::vector<std::size_t>{1, 2, 0, 3});
}

TEST_CASE("defaults are filled in for params not given") {
  const Graph g = load("version: 1\nnodes:\n  p: {type: test.params}\n");
  const Params& p = node(g, "p").params;
  CHECK(p.get<bool>("flag") == false);
  CHECK(p.get<std::int64_t>("count") == 3);
  CHECK(p.get<double>("ratio") == 0.5);
  CHECK(p.get<std::string>("name") == "anon");
  CHECK(p.get<std::string>("mode") == "fast");
  CHECK(p.get<std::string>("dst").empty());
  CHECK(p.get<std::vector<double>>("gravity") == std::vector<double>{0, -9.81, 0});
}

TEST_CASE("params are coerced to their declared types") {
  SECTION("bools") {
    for (const auto& [text, expected] : std::vector<std::pair<std::string, bool>>{{"true", true},
                                                                                  {"false", false},
                                                                                  {"yes", true},
                                                                                  {"no", false},
                                                                                  {"1", true},
                                                                                  {"0", false},
                                                                                  {"True", true},
                                                                                  {"NO", false},
                                                                                  {"\"yes\"", true}}) {
      INFO(text);
      const Graph g = load("version: 1\nnodes:\n  p: {type: test.params, params: {flag: " + text + "}}\n");
      CHECK(node(g, "p").params.get<bool>("flag") == expected);
    }
  }
  SECTION("numbers, quoted or not") {
    const Graph g = load(R"(version: 1
nodes:
  p: {type: test.params, params: {count: "+42", ratio: "1e-1", name: 12, mode: exact}}
)");
    const Params& p = node(g, "p").params;
    CHECK(p.get<std::int64_t>("count") == 42);
    CHECK(p.get<double>("ratio") == 0.1);
    CHECK(p.get<std::string>("name") == "12");
    CHECK(p.get<std::string>("mode") == "exact");
  }
  SECTION("float lists: a sequence, one number, or a string") {
    for (const auto& [text, expected] :
         std::vector<std::pair<std::string, std::vector<double>>>{{"[0, -9.81, 0]", {0, -9.81, 0}},
                                                                  {"[1]", {1}},
                                                                  {"[]", {}},
                                                                  {"2.5", {2.5}},
                                                                  {"\"0,-9.81,0\"", {0, -9.81, 0}},
                                                                  {"\"[0, -9.81, 0]\"", {0, -9.81, 0}},
                                                                  {"\"0 -9.81  0\"", {0, -9.81, 0}},
                                                                  {"\"\"", {}}}) {
      INFO(text);
      const Graph g = load("version: 1\nnodes:\n  p: {type: test.params, params: {gravity: " + text + "}}\n");
      CHECK(node(g, "p").params.get<std::vector<double>>("gravity") == expected);
    }
  }
}

TEST_CASE("variables: defaults, --set overrides, substitution whole and inside strings, $$ escapes") {
  const std::string text = R"YAML(version: 1
doc: variables
variables:
  ratio:   {default: "0.25", doc: "a ratio"}
  count:   {default: 7}
  dir:     {default: out, doc: "folder"}
  file:    {default: "${dir}/result.txt", doc: "defaults may use other variables"}
  input:   {required: true, doc: "the input"}
  gravity: {default: "0,-9.81,0"}
  mode:    {default: slow}
  empty:   {doc: "no default: empty"}
  extra:   {default: ""}
plugins: [kg_lowpass, "${dir}/plugins", "${extra}"]
nodes:
  p:
    type: test.params
    params:
      ratio: "${ratio}"
      count: ${count}
      name: "cost: $$5 for ${input} (${empty})"
      src: "${input}"
      dst: "${file}"
      gravity: "${gravity}"
      mode: ${mode}
  q: {type: test.params, params: {gravity: ["${count}", 2, "-${ratio}"], name: "$${dir}$x$"}}
)YAML";
  SECTION("defaults") {
    const Graph g = load(text, {{"input", "clip.bvh"}});
    const Params& p = node(g, "p").params;
    CHECK(p.get<double>("ratio") == 0.25);
    CHECK(p.get<std::int64_t>("count") == 7);
    CHECK(p.get<std::string>("name") == "cost: $5 for clip.bvh ()");
    CHECK(p.get<std::string>("src") == "clip.bvh");
    CHECK(p.get<std::string>("dst") == "out/result.txt");
    CHECK(p.get<std::vector<double>>("gravity") == std::vector<double>{0, -9.81, 0});
    CHECK(p.get<std::string>("mode") == "slow");
    const Params& q = node(g, "q").params;
    CHECK(q.get<std::vector<double>>("gravity") == std::vector<double>{7, 2, -0.25});
    CHECK(q.get<std::string>("name") == "${dir}$x$");
    CHECK(g.plugins == std::vector<std::string>{"kg_lowpass", "out/plugins"});  // the empty entry is dropped
    CHECK(g.values.at("file") == "out/result.txt");
    CHECK(g.values.at("empty").empty());
    REQUIRE(g.variables.size() == 9);
    CHECK(g.variables[0].name == "ratio");
    CHECK(g.variables[0].doc == "a ratio");
    CHECK(g.variables[4].name == "input");
    CHECK(g.variables[4].required);
    CHECK(g.variables[4].where.to_string() == "t.yaml:8:3");
  }
  SECTION("overrides are taken verbatim and reach defaults that use them") {
    const Graph g = load(text, {{"input", "a$b.bvh"},
                                {"ratio", "0.6"},
                                {"dir", "elsewhere"},
                                {"gravity", "[1, 2, 3]"},
                                {"mode", "exact"},
                                {"extra", "more_plugins"}});
    const Params& p = node(g, "p").params;
    CHECK(p.get<double>("ratio") == 0.6);
    CHECK(p.get<std::string>("src") == "a$b.bvh");
    CHECK(p.get<std::string>("dst") == "elsewhere/result.txt");
    CHECK(p.get<std::vector<double>>("gravity") == std::vector<double>{1, 2, 3});
    CHECK(p.get<std::string>("mode") == "exact");
    CHECK(g.plugins == std::vector<std::string>{"kg_lowpass", "elsewhere/plugins", "more_plugins"});
    CHECK(g.values.at("ratio") == "0.6");
  }
  SECTION("a variable of the wrong type for its param is an error at the param") {
    CHECK_THAT(
        load_error(text, {{"input", "x"}, {"ratio", "abc"}}),
        Catch::StartsWith("t.yaml:18:14: param 'ratio' of node 'p' (test.params) expects a float, got 'abc' "
                          "(from '${ratio}')"));
    CHECK_THAT(load_error(text, {{"input", "x"}, {"ratio", "2"}}),
               Catch::StartsWith(
                   "t.yaml:18:14: param 'ratio' of node 'p' (test.params) is 2.0, above its maximum 1.0"));
    CHECK_THAT(load_error(text, {{"input", "x"}, {"mode", "quick"}}),
               Catch::StartsWith(
                   "t.yaml:24:13: param 'mode' of node 'p' (test.params) must be one of fast, slow, exact; "
                   "got 'quick' (from '${mode}')"));
    CHECK_THAT(load_error(text, {{"input", "x"}, {"gravity", "0,,1"}}),
               Catch::StartsWith("t.yaml:23:16:") && Catch::Contains("empty element"));
    CHECK_THAT(
        load_error(text, {{"input", "x"}, {"count", "seven"}}),
        Catch::StartsWith("t.yaml:19:14: param 'count'") && Catch::Contains("expects an int, got 'seven'"));
    CHECK_THAT(load_error(text, {{"input", "x"}, {"count", "x"}}), Catch::Contains("expects an int"));
  }
  SECTION("the required variable must be given") {
    CHECK_THAT(load_error(text),
               Catch::StartsWith(
                   "t.yaml:8:3: variable 'input' is required and has no value: pass --set input=value"));
  }
  SECTION("--set of an undeclared variable is an error suggesting the nearest") {
    CHECK_THAT(load_error(text, {{"input", "x"}, {"ratoi", "1"}}),
               Catch::StartsWith(
                   "t.yaml: --set ratoi=1: the graph declares no variable 'ratoi'; did you mean 'ratio'?"));
  }
}

TEST_CASE("read_graph_plugins reads plugins without knowing node types") {
  const auto plugins = read_graph_plugins(kData / "v1_plugins.yaml", {{"plugin_dir", "/opt/kg"}});
  REQUIRE(plugins.size() == 3);
  std::vector<std::string> entries;
  for (const PluginEntry& p : plugins) entries.push_back(p.entry);
  CHECK(entries == std::vector<std::string>{"kg_lowpass", "/opt/kg/libextra.so", "relative/dir"});
  // Each with where it is written, for messages about it.
  CHECK(plugins[0].where.to_string().find("v1_plugins.yaml:7:5") != std::string::npos);
  CHECK(plugins[1].where.line == 8);
  CHECK(plugins[2].where.line == 9);
  CHECK_THROWS_WITH(read_graph_plugins(kData / "v1_plugins.yaml", {}),
                    Catch::Contains("v1_plugins.yaml:5:3: variable 'plugin_dir' is required"));
  // Loading it for real needs its node types.
  const Registry registry = kg_test::test_registry();
  CHECK_THROWS_WITH(load_graph(kData / "v1_plugins.yaml", registry, {{"plugin_dir", "/opt/kg"}}),
                    Catch::Contains("v1_plugins.yaml:11:18: unknown node type 'lowpass.filter'"));
  CHECK_THROWS_WITH(read_graph_plugins(kData / "no_such_file.yaml", {}),
                    Catch::Contains("no_such_file.yaml"));
}

TEST_CASE("old version 1 graph files still load") {
  const Registry registry = kg_test::test_registry();
  int loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kData)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("v1_", 0) != 0 || name == "v1_plugins.yaml") continue;
    INFO(name);
    const std::map<std::string, std::string> overrides =
        name == "v1_full.yaml" ? std::map<std::string, std::string>{{"input", "in.txt"}}
                               : std::map<std::string, std::string>{};
    CHECK_NOTHROW(load_graph(entry.path(), registry, overrides));
    ++loaded;
  }
  CHECK(loaded >= 3);
  const Graph g = load_graph(kData / "v1_full.yaml", registry, {{"input", "in.txt"}});
  CHECK(g.nodes.size() == 6);
  CHECK(g.connections.size() == 4);
  CHECK(node(g, "params").params.get<std::vector<double>>("gravity") == std::vector<double>{0, -1.62, 0});
}

namespace {

struct Invalid {
  const char* name;
  std::string yaml;
  std::vector<std::string> expected;  // substrings of what(); the first is the location prefix
  std::map<std::string, std::string> overrides{};
};

// clang-format off
const std::vector<Invalid> kInvalid = {
  {"missing version", "nodes:\n  a: {type: test.constant}\n",
   {"t.yaml:1:1: missing 'version: 1'", "reads graph format version 1"}},
  {"unsupported version", "version: 2\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml:1:10: unsupported graph format version '2'", "reads version 1"}},
  {"version not a number", "version: one\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml:1:10: unsupported graph format version 'one'"}},
  {"unknown top-level key", "version: 1\nnodez:\n  a: {type: test.constant}\n",
   {"t.yaml:2:1: unknown key 'nodez'; did you mean 'nodes'?"}},
  {"unknown node key", "version: 1\nnodes:\n  src:\n    type: test.constant\n    parms: {value: 1}\n",
   {"t.yaml:5:5: unknown key 'nodes.src.parms'; did you mean 'params'?", "allowed here: type, params, doc"}},
  {"unknown node type", "version: 1\nnodes:\n  a: {type: test.constnt}\n",
   {"t.yaml:3:13: unknown node type 'test.constnt' for node 'a'; did you mean 'test.constant'?"}},
  {"unknown node type, nothing near", "version: 1\nnodes:\n  a: {type: zzz.qqq}\n",
   {"t.yaml:3:13: unknown node type 'zzz.qqq' for node 'a'", "kinegraph nodes"}},
  {"node doc not text", "version: 1\nnodes:\n  a: {type: test.constant, doc: [x]}\n",
   {"t.yaml:3:33: 'nodes.a.doc' must be a single value, got a list"}},
  {"node without type", "version: 1\nnodes:\n  a: {params: {}}\n",
   {"t.yaml:3:3: node 'a' has no 'type'"}},
  {"unknown output port",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: a.output, to: b.in}\n",
   {"t.yaml:6:12: node 'a' (test.constant) has no output 'output'; did you mean 'out'?", "outputs: out (kg.Scalar)"}},
  {"unknown input port",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: a.out, to: b.inn}\n",
   {"t.yaml:6:23: node 'b' (test.scale) has no input 'inn'; did you mean 'in'?", "inputs: in (kg.Scalar)"}},
  {"port type mismatch",
   "version: 1\nnodes:\n  src: {type: test.motion_source}\n  solve: {type: test.scale}\nconnections:\n  - {from: src.motion, to: solve.in}\n",
   {"t.yaml:6:5: solve.in expects kg.Scalar, got kg.Motion from src.motion"}},
  {"connection from an input",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\n  c: {type: test.add}\nconnections:\n"
   "  - {from: a.out, to: b.in}\n  - {from: b.in, to: c.a}\n",
   {"t.yaml:8:12: b.in is an input of node 'b' (test.scale); a connection goes from an output to an input"}},
  {"connection to an output",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: a.out, to: b.out}\n",
   {"t.yaml:6:23: b.out is an output of node 'b' (test.scale)"}},
  {"unknown node in a connection",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: aa.out, to: b.in}\n",
   {"t.yaml:6:12: unknown node 'aa' in connections[0].from; did you mean 'a'?", "nodes: a, b"}},
  {"port reference without a dot",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: a, to: b.in}\n",
   {"t.yaml:6:12: 'connections[0].from' must be 'node.port', got 'a'"}},
  {"connection without 'to'",
   "version: 1\nnodes:\n  a: {type: test.constant}\nconnections:\n  - {from: a.out}\n",
   {"t.yaml:5:5: 'connections[0]' has no 'to'"}},
  {"unknown key in a connection",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n  - {from: a.out, too: b.in}\n",
   {"t.yaml:6:19: unknown key 'connections[0].too'; did you mean 'to'?"}},
  {"required input not connected", "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale}\n",
   {"t.yaml:4:3: required input b.in (kg.Scalar) of node 'b' (test.scale) is not connected", "outputs of that type: a.out"}},
  {"two connections into one input",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  c: {type: test.constant}\n  b: {type: test.scale}\nconnections:\n"
   "  - {from: a.out, to: b.in}\n  - {from: c.out, to: b.in}\n",
   {"t.yaml:8:5: input b.in has two connections: from a.out (t.yaml:7:5) and from c.out (t.yaml:8:5)"}},
  {"cycle",
   "version: 1\nnodes:\n  a: {type: test.scale}\n  b: {type: test.scale}\n  c: {type: test.scale}\nconnections:\n"
   "  - {from: a.out, to: b.in}\n  - {from: b.out, to: c.in}\n  - {from: c.out, to: a.in}\n",
   {"t.yaml:9:5: the graph has a cycle: a -> b -> c -> a"}},
  {"self loop", "version: 1\nnodes:\n  a: {type: test.scale}\nconnections:\n  - {from: a.out, to: a.in}\n",
   {"t.yaml:5:5: the graph has a cycle: a -> a"}},
  {"unknown param", "version: 1\nnodes:\n  a: {type: test.constant, params: {valeu: 1}}\n",
   {"t.yaml:3:37: unknown param 'valeu' for node 'a' (test.constant); did you mean 'value'?", "(params: value)"}},
  {"param of the wrong type", "version: 1\nnodes:\n  a: {type: test.constant, params: {value: abc}}\n",
   {"t.yaml:3:44: param 'value' of node 'a' (test.constant) expects a float, got 'abc'"}},
  {"param given a list", "version: 1\nnodes:\n  a: {type: test.constant, params: {value: [1, 2]}}\n",
   {"t.yaml:3:44: param 'value' of node 'a' (test.constant) expects a float, got a list"}},
  {"param without a value", "version: 1\nnodes:\n  a: {type: test.constant, params: {value: }}\n",
   {"t.yaml:3:37: param 'value' of node 'a' (test.constant) has no value"}},
  {"param above its maximum",
   "version: 1\nnodes:\n  a: {type: test.constant}\n  b: {type: test.scale, params: {factor: 11}}\nconnections:\n  - {from: a.out, to: b.in}\n",
   {"t.yaml:4:42: param 'factor' of node 'b' (test.scale) is 11.0, above its maximum 10.0 (allowed: -10.0 to 10.0)"}},
  {"int below its minimum", "version: 1\nnodes:\n  p: {type: test.params, params: {count: -1}}\n",
   {"t.yaml:3:42: param 'count' of node 'p' (test.params) is -1, below its minimum 0"}},
  {"enum not among its choices", "version: 1\nnodes:\n  p: {type: test.params, params: {mode: slo}}\n",
   {"t.yaml:3:41: param 'mode' of node 'p' (test.params) must be one of fast, slow, exact; got 'slo'; did you mean 'slow'?"}},
  {"bad bool", "version: 1\nnodes:\n  p: {type: test.params, params: {flag: maybe}}\n",
   {"t.yaml:3:41: param 'flag' of node 'p' (test.params) expects a bool", "got 'maybe'"}},
  {"int given a fraction", "version: 1\nnodes:\n  p: {type: test.params, params: {count: 2.5}}\n",
   {"t.yaml:3:42: param 'count' of node 'p' (test.params) expects an int, got '2.5'"}},
  {"float list element out of range", "version: 1\nnodes:\n  p: {type: test.params, params: {gravity: [0, -30, 0]}}\n",
   {"t.yaml:3:44: param 'gravity' of node 'p' (test.params) element 1 is -30.0, below its minimum -20.0"}},
  {"float list element not a number", "version: 1\nnodes:\n  p: {type: test.params, params: {gravity: [0, up, 0]}}\n",
   {"t.yaml:3:48: param 'gravity' of node 'p' (test.params): element 1 is 'up', not a number"}},
  {"missing required param", "version: 1\nnodes:\n  n: {type: test.needs}\n",
   {"t.yaml:3:3: node 'n' (test.needs) needs param 'path' (input_path: the file to read)"}},
  {"duplicate param", "version: 1\nnodes:\n  a: {type: test.constant, params: {value: 1, value: 2}}\n",
   {"t.yaml:3:47: duplicate key 'value' in 'nodes.a.params' (first at t.yaml:3:37)"}},
  {"undefined variable", "version: 1\nnodes:\n  n: {type: test.needs, params: {path: \"${input}\"}}\n",
   {"t.yaml:3:40: undefined variable 'input'", "declares no variables"}},
  {"undefined variable, near a declared one",
   "version: 1\nvariables:\n  input: {default: x}\nnodes:\n  n: {type: test.needs, params: {path: \"in/${inptu}.bvh\"}}\n",
   {"t.yaml:5:40: undefined variable 'inptu'; did you mean 'input'?", "(declared: input)"}},
  {"unterminated variable", "version: 1\nnodes:\n  n: {type: test.needs, params: {path: \"${input\"}}\n",
   {"t.yaml:3:40: unterminated '${' in '${input'"}},
  {"bad variable reference", "version: 1\nnodes:\n  n: {type: test.needs, params: {path: \"${in put}\"}}\n",
   {"t.yaml:3:40: bad variable reference '${in put}'"}},
  {"required variable without value",
   "version: 1\nvariables:\n  input: {required: true, doc: \"the clip\"}\nnodes:\n  n: {type: test.needs, params: {path: \"${input}\"}}\n",
   {"t.yaml:3:3: variable 'input' is required and has no value: pass --set input=value (the clip)"}},
  {"--set of an undeclared variable",
   "version: 1\nvariables:\n  input: {default: x}\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml: --set inptu=y: the graph declares no variable 'inptu'; did you mean 'input'? (declared: input)"},
   {{"inptu", "y"}}},
  {"required variable with a default", "version: 1\nvariables:\n  x: {required: true, default: 3}\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml:3:23: variable 'x' is required, so it takes no default"}},
  {"unknown key in a variable", "version: 1\nvariables:\n  x: {dflt: 3}\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml:3:7: unknown key 'variables.x.dflt'; did you mean 'default'?"}},
  {"variables referring to each other",
   "version: 1\nvariables:\n  a: {default: \"${b}\"}\n  b: {default: \"x${a}\"}\nnodes:\n  n: {type: test.constant}\n",
   {"t.yaml:3:3: variable defaults refer to each other in a cycle: a -> b -> a"}},
  {"duplicate node id", "version: 1\nnodes:\n  a: {type: test.constant}\n  a: {type: test.constant}\n",
   {"t.yaml:4:3: duplicate key 'a' in 'nodes' (first at t.yaml:3:3)"}},
  {"bad node id", "version: 1\nnodes:\n  a.b: {type: test.constant}\n",
   {"t.yaml:3:3: node id 'a.b' may hold only letters, digits, '_' and '-'"}},
  {"duplicate top-level key", "version: 1\nnodes:\n  a: {type: test.constant}\nnodes:\n  b: {type: test.constant}\n",
   {"t.yaml:4:1: duplicate key 'nodes' at the top level (first at t.yaml:2:1)"}},
  {"nodes not a map", "version: 1\nnodes: [a, b]\n", {"t.yaml:2:8: 'nodes' must be a map, got a list"}},
  {"no nodes", "version: 1\ndoc: nothing\n", {"t.yaml:1:1: the graph has no nodes"}},
  {"empty file", "", {"t.yaml:1:1: empty graph file"}},
  {"not a map", "- version: 1\n", {"t.yaml:1:1: a graph file must be a map"}},
  {"malformed YAML", "version: 1\nnodes:\n  a: {type: test.constant\n", {"t.yaml:4:1: malformed YAML"}},
  {"malformed YAML, bad indentation", "version: 1\nnodes:\n  a: {type: test.constant}\n b: 2\n", {"t.yaml:4:2: malformed YAML"}},
  {"output path equal to an input path", "version: 1\nnodes:\n  p: {type: test.params, params: {src: in.txt, dst: ./in.txt}}\n",
   {"t.yaml:3:53: param 'dst' of node 'p' would overwrite input 'in.txt' (read by param 'src' of node 'p' at t.yaml:3:40): './in.txt' is the same file"}},
  {"output path equal to another node's input path",
   "version: 1\nnodes:\n  r: {type: test.needs, params: {path: data/../in.txt}}\n  p: {type: test.params, params: {dst: in.txt}}\n",
   {"t.yaml:4:40: param 'dst' of node 'p' would overwrite input 'data/../in.txt' (read by param 'path' of node 'r' at t.yaml:3:40)"}},
  {"two outputs to one file",
   "version: 1\nnodes:\n  p: {type: test.params, params: {dst: o.txt}}\n  q: {type: test.params, params: {dst: o.txt}}\n",
   {"t.yaml:4:40: param 'dst' of node 'q' writes 'o.txt', which param 'dst' of node 'p' (t.yaml:3:40) writes too"}},
  {"a factory that throws", "version: 1\nnodes:\n  f: {type: test.bad_factory, params: {lo: 2, hi: 1}}\n",
   {"t.yaml:3:3: node 'f' (test.bad_factory): lo must not exceed hi"}},
  {"plugins not a list", "version: 1\nplugins: kg_lowpass\nnodes:\n  a: {type: test.constant}\n",
   {"t.yaml:2:10: 'plugins' must be a list"}},
};
// clang-format on

}  // namespace

TEST_CASE("invalid graphs are refused with file:line:column and the names involved") {
  for (const Invalid& c : kInvalid) {
    INFO("case: " << c.name << "\n--- yaml ---\n" << c.yaml << "------------");
    const std::string what = load_error(c.yaml, c.overrides);
    REQUIRE_FALSE(c.expected.empty());
    CHECK_THAT(what, Catch::StartsWith(c.expected.front()));
    for (std::size_t i = 1; i < c.expected.size(); ++i) CHECK_THAT(what, Catch::Contains(c.expected[i]));
  }
}

TEST_CASE("invalid graph files are refused with their path, line and column") {
  const Registry registry = kg_test::test_registry();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"invalid_type_mismatch.yaml", ":14:5: solve.a expects kg.Scalar, got kg.Motion from src.motion"},
      {"invalid_cycle.yaml", ":12:5: the graph has a cycle: first -> second -> first"},
      {"invalid_version.yaml", ":2:10: unsupported graph format version '3'; this kinegraph reads version 1"},
      {"invalid_malformed.yaml", ":5:"},
      {"invalid_overwrite.yaml", ":8:43: param 'dst' of node 'copy' would overwrite input"},
  };
  for (const auto& [file, expected] : cases) {
    INFO(file);
    const auto path = kData / file;
    REQUIRE(std::filesystem::exists(path));
    try {
      load_graph(path, registry, {});
      FAIL("no error for " << file);
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Catch::StartsWith(path.string() + expected));
      CHECK(e.where().file == path.string());
    }
  }
}
