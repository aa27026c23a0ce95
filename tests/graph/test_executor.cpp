// The executor: order, values, failures and what they skip, parallel branches, reports.
#include <catch2/catch.hpp>

#include <iostream>

#include "../support/temp_dir.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/yaml_io.hpp"
#include "test_nodes.hpp"

using namespace kg;
using namespace kg::graph;
using kg_test::TestAnswer;
using kg_test::TestQuestion;

namespace {

struct Logged {
  std::mutex mutex;
  std::vector<std::pair<std::string, std::string>> lines;
  RunOptions options(int jobs) {
    RunOptions o;
    o.jobs = jobs;
    o.on_log = [this](const std::string& id, const std::string& message) {
      std::lock_guard<std::mutex> lock(mutex);
      lines.emplace_back(id, message);
    };
    return o;
  }
  bool has(const std::string& id, const std::string& part) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& [i, m] : lines)
      if (i == id && m.find(part) != std::string::npos) return true;
    return false;
  }
};

const NodeRun& run_of(const RunResult& r, const std::string& id) {
  for (const NodeRun& n : r.nodes)
    if (n.id == id) return n;
  FAIL("no node " << id << " in the result");
  throw std::logic_error("unreachable");
}

const char* kArithmetic = R"(version: 1
nodes:
  twice: {type: test.scale, params: {factor: 2}}
  sum: {type: test.add}
  a: {type: test.constant, params: {value: 2}}
  b: {type: test.constant, params: {value: 3}}
  alone: {type: test.add}
  c: {type: test.constant, params: {value: 10}}
connections:
  - {from: sum.sum, to: twice.in}
  - {from: a.out, to: sum.a}
  - {from: b.out, to: sum.b}
  - {from: c.out, to: alone.a}
)";

}  // namespace

TEST_CASE("nodes run in topological order and values flow along connections") {
  auto journal = std::make_shared<kg_test::Journal>();
  const Registry registry = kg_test::test_registry(journal);
  const Graph g = load_graph_from_string(kArithmetic, "arith.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  CHECK(r.ok);
  REQUIRE(r.nodes.size() == 6);
  CHECK(r.nodes[0].id == "twice");  // the graph's node order, whatever the run order
  for (const NodeRun& n : r.nodes) {
    CHECK(n.status == NodeStatus::Ok);
    CHECK(n.message.empty());
    CHECK(n.wall_seconds >= 0);
  }
  CHECK(r.outputs.at("sum.sum").get<double>() == 5.0);
  CHECK(r.outputs.at("twice.out").get<double>() == 10.0);
  CHECK(r.outputs.at("alone.sum").get<double>() == 10.0);
  CHECK(r.outputs.size() == 6);
  // One thread: exactly the graph's stable topological order.
  std::vector<std::string> expected;
  for (std::size_t i : g.topological_order()) expected.push_back(g.nodes[i].id);
  CHECK(journal->ran == expected);
  CHECK(journal->ran == std::vector<std::string>{"a", "b", "sum", "twice", "c", "alone"});
  // Figures, and an optional input seen as absent.
  const NodeRun& alone = run_of(r, "alone");
  REQUIRE(alone.figures.size() == 1);
  CHECK(alone.figures[0].first == "b_connected");
  CHECK(std::get<bool>(alone.figures[0].second) == false);
  CHECK(std::get<bool>(run_of(r, "sum").figures[0].second) == true);
  CHECK(r.wall_seconds >= 0);
}

TEST_CASE("a graph runs again, and with many threads, to the same values") {
  auto journal = std::make_shared<kg_test::Journal>();
  const Registry registry = kg_test::test_registry(journal);
  const Graph g = load_graph_from_string(kArithmetic, "arith.yaml", registry);
  for (int jobs : {1, 2, 4, 16, 0, -3}) {
    INFO("jobs " << jobs);
    journal->ran.clear();
    const RunResult r = run_graph(g, registry, {.jobs = jobs, .on_log = {}});
    CHECK(r.ok);
    CHECK(r.outputs.at("twice.out").get<double>() == 10.0);
    // Whatever the interleaving, every node ran once and after its inputs.
    REQUIRE(journal->ran.size() == 6);
    auto pos = [&](const std::string& id) {
      return std::find(journal->ran.begin(), journal->ran.end(), id) - journal->ran.begin();
    };
    CHECK(pos("a") < pos("sum"));
    CHECK(pos("b") < pos("sum"));
    CHECK(pos("sum") < pos("twice"));
    CHECK(pos("c") < pos("alone"));
  }
}

TEST_CASE("a wide and deep graph gives the same results on 1 and 4 threads") {
  // 40 chains of 10 nodes each, every chain adding 1 per node on top of its own constant.
  std::string text = "version: 1\nnodes:\n";
  std::string wires = "connections:\n";
  for (int c = 0; c < 40; ++c) {
    text +=
        "  c" + std::to_string(c) + ": {type: test.constant, params: {value: " + std::to_string(c) + "}}\n";
    for (int k = 0; k < 10; ++k) {
      const std::string id = "n" + std::to_string(c) + "_" + std::to_string(k);
      const std::string prev =
          k == 0 ? "c" + std::to_string(c) : "n" + std::to_string(c) + "_" + std::to_string(k - 1);
      text += "  " + id + ": {type: test.sleep, params: {ms: 0}}\n";
      wires += "  - {from: " + prev + ".out, to: " + id + ".in}\n";
    }
  }
  const Registry registry = kg_test::test_registry();
  const Graph g = load_graph_from_string(text + wires, "wide.yaml", registry);
  REQUIRE(g.nodes.size() == 440);
  const RunResult one = run_graph(g, registry, {.jobs = 1, .on_log = {}});
  const RunResult four = run_graph(g, registry, {.jobs = 4, .on_log = {}});
  REQUIRE(one.ok);
  REQUIRE(four.ok);
  for (int c = 0; c < 40; ++c) {
    const std::string last = "n" + std::to_string(c) + "_9.out";
    CHECK(one.outputs.at(last).get<double>() == c + 10.0);
    CHECK(four.outputs.at(last).get<double>() == c + 10.0);
  }
}

TEST_CASE("independent branches really run at the same time with jobs=2") {
  const char* text = R"(version: 1
nodes:
  left: {type: test.meet, params: {timeout_ms: 10000}}
  right: {type: test.meet, params: {timeout_ms: 10000}}
)";
  auto rendezvous = std::make_shared<kg_test::Rendezvous>();
  const Registry registry = kg_test::test_registry({}, rendezvous);
  const Graph g = load_graph_from_string(text, "meet.yaml", registry);
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_graph(g, registry, {.jobs = 2, .on_log = {}});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE(r.ok);
  // Each node waited for the other: only possible if both ran at once.
  CHECK(r.outputs.at("left.met").get<bool>());
  CHECK(r.outputs.at("right.met").get<bool>());
  CHECK(seconds < 5.0);
}

TEST_CASE("with jobs=1 the same graph runs one node at a time and does not hang") {
  const char* text = R"(version: 1
nodes:
  left: {type: test.meet, params: {timeout_ms: 100}}
  right: {type: test.meet, params: {timeout_ms: 100}}
)";
  auto rendezvous = std::make_shared<kg_test::Rendezvous>();
  const Registry registry = kg_test::test_registry({}, rendezvous);
  const Graph g = load_graph_from_string(text, "meet.yaml", registry);
  const RunResult r = run_graph(g, registry, {.jobs = 1, .on_log = {}});
  REQUIRE(r.ok);
  // The first waited alone until its timeout; the second found it had arrived.
  CHECK_FALSE(r.outputs.at("left.met").get<bool>());
  CHECK(r.outputs.at("right.met").get<bool>());
}

TEST_CASE("parallel sleeps overlap: two 300 ms branches take well under 600 ms with jobs=2") {
  const char* text = R"(version: 1
nodes:
  a: {type: test.sleep, params: {ms: 300}}
  b: {type: test.sleep, params: {ms: 300}}
)";
  const Registry registry = kg_test::test_registry();
  const Graph g = load_graph_from_string(text, "sleep.yaml", registry);
  const RunResult serial = run_graph(g, registry, {.jobs = 1, .on_log = {}});
  const RunResult parallel = run_graph(g, registry, {.jobs = 2, .on_log = {}});
  CHECK(serial.wall_seconds >= 0.6);
  CHECK(parallel.wall_seconds < 0.55);
  CHECK(run_of(parallel, "a").wall_seconds >= 0.3);
}

TEST_CASE("a failing node is reported, its downstream skipped, other branches still run") {
  const char* text = R"(version: 1
nodes:
  src: {type: test.constant, params: {value: 1}}
  bad: {type: test.fail, params: {message: "solver exploded"}}
  after: {type: test.scale}
  later: {type: test.add}
  also_bad: {type: test.fail, params: {message: "second failure"}}
  both: {type: test.add}
  fine: {type: test.scale, params: {factor: 3}}
connections:
  - {from: src.out, to: bad.in}
  - {from: bad.out, to: after.in}
  - {from: after.out, to: later.a}
  - {from: src.out, to: fine.in}
  - {from: later.sum, to: both.a}
  - {from: also_bad.out, to: both.b}
)";
  for (int jobs : {1, 3}) {
    INFO("jobs " << jobs);
    const Registry registry = kg_test::test_registry();
    const Graph g = load_graph_from_string(text, "fail.yaml", registry);
    Logged log;
    const RunResult r = run_graph(g, registry, log.options(jobs));
    CHECK_FALSE(r.ok);
    CHECK(run_of(r, "src").status == NodeStatus::Ok);
    CHECK(run_of(r, "fine").status == NodeStatus::Ok);
    CHECK(r.outputs.at("fine.out").get<double>() == 3.0);
    const NodeRun& bad = run_of(r, "bad");
    CHECK(bad.status == NodeStatus::Failed);
    CHECK(bad.message == "solver exploded");
    const NodeRun& after = run_of(r, "after");
    CHECK(after.status == NodeStatus::Skipped);
    CHECK(after.message == "not run: upstream node 'bad' failed");
    CHECK(run_of(r, "later").status == NodeStatus::Skipped);
    CHECK(run_of(r, "later").message ==
          "not run: upstream node 'bad' failed");  // the cause, not the skipped parent
    const NodeRun& both = run_of(r, "both");
    CHECK(both.status == NodeStatus::Skipped);
    CHECK_THAT(both.message,
               Catch::Contains("nodes") && Catch::Contains("'bad'") && Catch::Contains("'also_bad'"));
    CHECK(r.outputs.count("after.out") == 0);
    CHECK(r.outputs.count("src.out") == 1);
    CHECK(log.has("bad", "about to fail"));
    CHECK(log.has("bad", "failed: solver exploded"));
    CHECK(log.has("also_bad", "failed: second failure"));
  }
}

TEST_CASE("an output a node did not set fails its consumer with a clear message") {
  const char* text = R"(version: 1
nodes:
  quiet: {type: test.silent}
  use: {type: test.scale}
  next: {type: test.scale}
connections:
  - {from: quiet.out, to: use.in}
  - {from: use.out, to: next.in}
)";
  const Registry registry = kg_test::test_registry();
  const Graph g = load_graph_from_string(text, "silent.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  CHECK_FALSE(r.ok);
  CHECK(run_of(r, "quiet").status == NodeStatus::Ok);
  CHECK(run_of(r, "use").status == NodeStatus::Failed);
  CHECK_THAT(run_of(r, "use").message, Catch::StartsWith("input use.in not produced by quiet.out"));
  CHECK(run_of(r, "next").status == NodeStatus::Skipped);
  CHECK_THAT(run_of(r, "next").message, Catch::Contains("'use'"));
  CHECK(log.has("use", "not produced by quiet.out"));
}

TEST_CASE("an output of the wrong type, or an undeclared input, fails the node") {
  const char* text = R"(version: 1
nodes:
  wrong: {type: test.wrong_type}
  ghost: {type: test.undeclared_input}
)";
  const Registry registry = kg_test::test_registry();
  const Graph g = load_graph_from_string(text, "wrong.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(2));
  CHECK(run_of(r, "wrong").status == NodeStatus::Failed);
  CHECK_THAT(run_of(r, "wrong").message,
             Catch::Contains("wrong.out is declared kg.Scalar") && Catch::Contains("kg.String"));
  CHECK(run_of(r, "ghost").status == NodeStatus::Failed);
  CHECK_THAT(run_of(r, "ghost").message, Catch::Contains("'ghost'") && Catch::Contains("does not declare"));
  CHECK(r.outputs.empty());
}

TEST_CASE("the default log prints [node] message to stderr") {
  const Registry registry = kg_test::test_registry();
  const Graph g =
      load_graph_from_string("version: 1\nnodes:\n  f: {type: test.figures}\n", "f.yaml", registry);
  std::ostringstream captured;
  auto* old = std::cerr.rdbuf(captured.rdbuf());
  const RunResult r = run_graph(g, registry);
  std::cerr.rdbuf(old);
  CHECK(r.ok);
  CHECK(captured.str() == "[f] reported\n");
}

TEST_CASE("values made by a plugin's node keep the plugin alive") {
  auto owner = std::make_shared<int>(1);
  std::weak_ptr<int> watch = owner;
  RunResult r;
  {
    Registry registry = kg_test::test_registry();
    NodeSpec s{"plugin.make", 1, "", {}, {{"out", "kg.Scalar", true, ""}}, {}};
    registry.add_node({s,
                       [](const Params&) {
                         return kg_test::make_fn_node([](RunContext& ctx) { ctx.output("out", 4.0); });
                       }},
                      owner, "/plugins/fake.so");
    owner.reset();
    const Graph g = load_graph_from_string(
        "version: 1\nnodes:\n  p: {type: plugin.make}\n  s: {type: test.scale}\nconnections:\n  - {from: "
        "p.out, to: s.in}\n",
        "p.yaml", registry);
    r = run_graph(g, registry);
    REQUIRE(r.ok);
  }
  // Registry and graph are gone; the plugin's value still holds the library.
  CHECK_FALSE(watch.expired());
  CHECK(r.outputs.at("p.out").get<double>() == 4.0);
  r.outputs.erase("s.out");  // made by a built-in: holds nothing
  CHECK_FALSE(watch.expired());
  r.outputs.clear();
  CHECK(watch.expired());
}

TEST_CASE("the report holds per-node status, times and figures as JSON") {
  const char* text = R"(version: 1
variables:
  msg: {default: "it \"broke\""}
nodes:
  f: {type: test.figures}
  bad: {type: test.fail, params: {message: "${msg}"}}
  after: {type: test.scale}
connections:
  - {from: bad.out, to: after.in}
)";
  const Registry registry = kg_test::test_registry();
  const Graph g = load_graph_from_string(text, "report.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  kg::test::TempDir dir;
  const auto file = dir / "reports" / "run.json";
  write_report_json(file, g, r);
  const std::string json = kg::test::read_file(file);
  CHECK_THAT(json, Catch::Contains("\"graph\": \"report.yaml\""));
  CHECK_THAT(json, Catch::Contains("\"ok\": false"));
  CHECK_THAT(json, Catch::Contains("\"variables\": {\n    \"msg\": \"it \\\"broke\\\"\"\n  }"));
  CHECK_THAT(json,
             Catch::Contains("\"id\": \"f\",\n      \"type\": \"test.figures\",\n      \"status\": \"ok\""));
  CHECK_THAT(json,
             Catch::Contains(
                 "\"figures\": {\n        \"iterations\": 43,\n        \"residual\": 0.125,\n"
                 "        \"converged\": true,\n        \"note\": \"tab\\there \\\"quoted\\\"\"\n      }"));
  CHECK_THAT(json, Catch::Contains("\"status\": \"failed\",\n      \"message\": \"it \\\"broke\\\"\""));
  CHECK_THAT(json,
             Catch::Contains(
                 "\"status\": \"skipped\",\n      \"message\": \"not run: upstream node 'bad' failed\""));
  CHECK_THAT(json, Catch::Contains("\"wall_seconds\": "));
  CHECK(json.back() == '\n');
  // Balanced braces and brackets outside strings: a cheap well-formedness check.
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if (c == '}' || c == ']') {
      --depth;
      CHECK(depth >= 0);
    }
  }
  CHECK(depth == 0);
  CHECK_FALSE(in_string);
}

TEST_CASE("a running node finds the registry's extensions through its context") {
  // How a solver node meets a plugin's constraint kinds: RunContext::find<T>.
  Registry registry;
  registry.add_extension(Extension::make<TestAnswer>(
      "answer", std::make_shared<const TestAnswer>(TestAnswer{42.0}), "a number"));
  NodeSpec s{"test.lookup", 1, "Outputs the extension it finds, or -1.", {}, {{"out", "kg.Scalar", true, "a number"}}, {}};
  registry.add_node({s, [](const Params&) {
                       return kg_test::make_fn_node([](RunContext& ctx) {
                         const std::shared_ptr<const TestAnswer> found = ctx.find<TestAnswer>("answer");
                         const auto missing = ctx.find<TestAnswer>("question");
                         const auto other = ctx.find<TestQuestion>("answer");  // same name, other interface
                         ctx.output("out", found && !missing && !other ? found->value : -1.0);
                       });
                     }});
  const Graph g = load_graph_from_string("version: 1\nnodes:\n  look: {type: test.lookup}\n", "lookup.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  REQUIRE(r.ok);
  CHECK(r.outputs.at("look.out").get<double>() == 42.0);
}
