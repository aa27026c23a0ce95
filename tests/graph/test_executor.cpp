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
  NodeSpec s{"test.lookup",
             1,
             "Outputs the extension it finds, or -1.",
             {},
             {{"out", "kg.Scalar", true, "a number"}},
             {}};
  registry.add_node({s, [](const Params&) {
                       return kg_test::make_fn_node([](RunContext& ctx) {
                         const std::shared_ptr<const TestAnswer> found = ctx.find<TestAnswer>("answer");
                         const auto missing = ctx.find<TestAnswer>("question");
                         const auto other = ctx.find<TestQuestion>("answer");  // same name, other interface
                         ctx.output("out", found && !missing && !other ? found->value : -1.0);
                       });
                     }});
  const Graph g =
      load_graph_from_string("version: 1\nnodes:\n  look: {type: test.lookup}\n", "lookup.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  REQUIRE(r.ok);
  CHECK(r.outputs.at("look.out").get<double>() == 42.0);
}

// Caching and effects (DESIGN.md 13): nodes with the same key compute once; sinks always run;
// values are freed after their last consumer; a report set before a failure still reaches its sink.

TEST_CASE("nodes of one run with the same type, params and inputs compute once", "[cache]") {
  const char* text = R"(version: 1
nodes:
  a: {type: test.constant, params: {value: 2}}
  b: {type: test.constant, params: {value: 2}}
  other: {type: test.constant, params: {value: 3}}
  twice_a: {type: test.scale, params: {factor: 2}}
  twice_b: {type: test.scale, params: {factor: 2}}
  thrice_b: {type: test.scale, params: {factor: 3}}
  twice_other: {type: test.scale, params: {factor: 2}}
connections:
  - {from: a.out, to: twice_a.in}
  - {from: b.out, to: twice_b.in}
  - {from: b.out, to: thrice_b.in}
  - {from: other.out, to: twice_other.in}
)";
  for (int jobs : {1, 3}) {
    INFO("jobs " << jobs);
    auto journal = std::make_shared<kg_test::Journal>();
    const Registry registry = kg_test::test_registry(journal);
    const Graph g = load_graph_from_string(text, "same.yaml", registry);
    Logged log;
    const RunResult r = run_graph(g, registry, log.options(jobs));
    REQUIRE(r.ok);
    // b is a; twice_b's producer has a's key, so it is twice_a too.
    CHECK(run_of(r, "b").same_as == "a");
    CHECK(run_of(r, "twice_b").same_as == "twice_a");
    CHECK(run_of(r, "b").key == run_of(r, "a").key);
    CHECK(run_of(r, "b").status == NodeStatus::Ok);
    // Other params, other inputs: their own runs.
    for (const std::string id : {"a", "other", "twice_a", "thrice_b", "twice_other"}) {
      CHECK(run_of(r, id).same_as.empty());
      CHECK(run_of(r, id).key.size() == 64);
    }
    CHECK(run_of(r, "thrice_b").key != run_of(r, "twice_b").key);
    CHECK(run_of(r, "twice_other").key != run_of(r, "twice_a").key);
    std::vector<std::string> ran = journal->ran;
    std::sort(ran.begin(), ran.end());
    CHECK(ran == std::vector<std::string>{"a", "other", "thrice_b", "twice_a", "twice_other"});
    CHECK(log.has("b", "same_as: a"));
    CHECK(log.has("twice_b", "same_as: twice_a"));
    // The taken results are the first's values themselves.
    CHECK(&r.outputs.at("twice_b.out").get<double>() == &r.outputs.at("twice_a.out").get<double>());
    CHECK(r.outputs.at("thrice_b.out").get<double>() == 6.0);
  }
}

TEST_CASE("a node taking another's results takes its figures, and its failure with the same message",
          "[cache]") {
  const char* text = R"(version: 1
nodes:
  f1: {type: test.figures}
  f2: {type: test.figures}
  bad1: {type: test.fail, params: {message: "solver exploded"}}
  bad2: {type: test.fail, params: {message: "solver exploded"}}
  after2: {type: test.scale}
connections:
  - {from: bad2.out, to: after2.in}
)";
  for (int jobs : {1, 2}) {
    INFO("jobs " << jobs);
    const Registry registry = kg_test::test_registry();
    const Graph g = load_graph_from_string(text, "same_fail.yaml", registry);
    Logged log;
    const RunResult r = run_graph(g, registry, log.options(jobs));
    CHECK_FALSE(r.ok);
    CHECK(run_of(r, "f2").same_as == "f1");
    CHECK(run_of(r, "f2").figures == run_of(r, "f1").figures);
    CHECK(run_of(r, "f2").figures.size() == 4);
    const NodeRun& bad2 = run_of(r, "bad2");
    CHECK(bad2.same_as == "bad1");
    CHECK(bad2.status == NodeStatus::Failed);
    CHECK(bad2.message == "solver exploded");
    CHECK(log.has("bad2", "failed: solver exploded"));
    CHECK(run_of(r, "after2").status == NodeStatus::Skipped);
    CHECK(run_of(r, "after2").message == "not run: upstream node 'bad2' failed");

    kg::test::TempDir dir;
    write_report_json(dir / "report.json", g, r);
    const std::string json = kg::test::read_file(dir / "report.json");
    CHECK_THAT(json, Catch::Contains("\"id\": \"f2\"") && Catch::Contains("\"same_as\": \"f1\""));
    CHECK_THAT(json, Catch::Contains("\"same_as\": \"\""));
  }
}

namespace {

// Nodes that watch a value's life: test.hold outputs a fresh string and keeps a weak reference to
// it in `probe`; test.pass copies its input string; test.alive reports (figure `alive`) whether
// the watched string still lives when it runs.
Registry lifetime_registry(std::shared_ptr<std::weak_ptr<const std::string>> probe) {
  Registry r = kg_test::test_registry();
  auto string_port = [](const std::string& name) { return PortSpec{name, "kg.String", true, "text"}; };
  r.add_node({NodeSpec{"test.hold", 1, "Outputs a string it watches.", {}, {string_port("out")}, {}},
              [probe](const Params&) {
                return kg_test::make_fn_node([probe](RunContext& ctx) {
                  auto value = std::make_shared<const std::string>("held");
                  *probe = value;
                  ctx.set_output("out", Value::share(value));
                });
              }});
  r.add_node({NodeSpec{"test.pass", 1, "Copies its string.", {string_port("in")}, {string_port("out")}, {}},
              [](const Params&) {
                return kg_test::make_fn_node(
                    [](RunContext& ctx) { ctx.output("out", std::string(ctx.input<std::string>("in"))); });
              }});
  r.add_node({NodeSpec{"test.alive", 1, "Whether the watched string lives.", {string_port("text")}, {}, {}},
              [probe](const Params&) {
                return kg_test::make_fn_node(
                    [probe](RunContext& ctx) { ctx.report("alive", !probe->expired()); });
              }});
  return r;
}

}  // namespace

TEST_CASE("a value is freed after its last consumer unless keep_outputs", "[cache]") {
  // hold -> pass -> alive: alive runs after pass, hold's only consumer, has run.
  const char* text = R"(version: 1
nodes:
  hold: {type: test.hold}
  pass: {type: test.pass}
  alive: {type: test.alive}
connections:
  - {from: hold.out, to: pass.in}
  - {from: pass.out, to: alive.text}
)";
  auto probe = std::make_shared<std::weak_ptr<const std::string>>();
  const Registry registry = lifetime_registry(probe);
  const Graph g = load_graph_from_string(text, "life.yaml", registry);
  RunOptions options;
  options.on_log = [](const std::string&, const std::string&) {};

  options.keep_outputs = false;
  const RunResult freed = run_graph(g, registry, options);
  REQUIRE(freed.ok);
  CHECK(freed.outputs.empty());
  CHECK(std::get<bool>(run_of(freed, "alive").figures.at(0).second) == false);
  CHECK(probe->expired());

  options.keep_outputs = true;
  const RunResult kept = run_graph(g, registry, options);
  REQUIRE(kept.ok);
  CHECK(std::get<bool>(run_of(kept, "alive").figures.at(0).second) == true);
  CHECK(kept.outputs.at("hold.out").get<std::string>() == "held");
  CHECK(kept.outputs.size() == 2);
}

TEST_CASE("the executor never merges nodes with side effects, nor nodes writing files", "[cache]") {
  const char* text = R"(version: 1
nodes:
  src: {type: test.constant, params: {value: 1}}
  s1: {type: test.sleep, params: {ms: 0}}
  s2: {type: test.sleep, params: {ms: 0}}
connections:
  - {from: src.out, to: s1.in}
  - {from: src.out, to: s2.in}
)";
  auto journal = std::make_shared<kg_test::Journal>();
  const Registry registry = kg_test::test_registry(journal);
  const Graph g = load_graph_from_string(text, "sinks.yaml", registry);
  const RunResult r = run_graph(g, registry, {.jobs = 1, .on_log = {}});
  REQUIRE(r.ok);
  CHECK(run_of(r, "s1").key == run_of(r, "s2").key);
  CHECK(run_of(r, "s2").same_as.empty());
  CHECK(journal->ran.size() == 3);
  NodeSpec writer{"test.writer", 1, "", {}, {}, {{"path", ParamType::OutputPath, std::string(), ""}}};
  CHECK(writer.has_side_effects());
  CHECK_FALSE(NodeSpec{"test.pure", 1, ""}.has_side_effects());
}

TEST_CASE("an output kept on failure reaches its consumers, the others skip", "[cache]") {
  Registry registry = kg_test::test_registry();
  auto string_port = [](const std::string& name) { return PortSpec{name, "kg.String", true, "text"}; };
  PortSpec why = string_port("why");
  why.kept_on_failure = true;
  registry.add_node(
      {NodeSpec{"test.give_up", 1, "Sets why, then fails.", {}, {why, kg_test::scalar_port("out")}, {}},
       [](const Params&) {
         return kg_test::make_fn_node([](RunContext& ctx) {
           ctx.output("why", std::string("out of reach"));
           ctx.output("out", 1.0);
           throw std::runtime_error("gave up");
         });
       }});
  registry.add_node(
      {NodeSpec{"test.say", 1, "Logs its string.", {string_port("in")}, {}, {}}, [](const Params&) {
         return kg_test::make_fn_node(
             [](RunContext& ctx) { ctx.log("says " + ctx.input<std::string>("in")); });
       }});
  const char* text = R"(version: 1
nodes:
  solver: {type: test.give_up}
  say: {type: test.say}
  after: {type: test.scale}
connections:
  - {from: solver.why, to: say.in}
  - {from: solver.out, to: after.in}
)";
  const Graph g = load_graph_from_string(text, "kept.yaml", registry);
  Logged log;
  const RunResult r = run_graph(g, registry, log.options(1));
  CHECK_FALSE(r.ok);
  CHECK(run_of(r, "solver").status == NodeStatus::Failed);
  CHECK(run_of(r, "solver").message == "gave up");
  CHECK(run_of(r, "say").status == NodeStatus::Ok);
  CHECK(log.has("say", "says out of reach"));
  CHECK(run_of(r, "after").status == NodeStatus::Skipped);
  CHECK(r.outputs.count("solver.why") == 1);
  CHECK(r.outputs.count("solver.out") == 0);
}
