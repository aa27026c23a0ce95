// Small node types for the graph tests: they exercise the executor and the loader without
// anything of motion. Registered through the same Registry API as built-ins and plugins.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"

namespace kg_test {

using namespace kg;
using namespace kg::graph;

// Two parties meet, or give up after a timeout: proves two nodes really run at the same time
// with jobs=2, and cannot hang with jobs=1.
struct Rendezvous {
  std::mutex mutex;
  std::condition_variable cv;
  int arrived = 0;

  bool meet(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex);
    ++arrived;
    cv.notify_all();
    return cv.wait_for(lock, timeout, [&] { return arrived >= 2; });
  }
};

// Which nodes ran, in which order (shared by the nodes of one registry).
struct Journal {
  std::mutex mutex;
  std::vector<std::string> ran;
  void add(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex);
    ran.push_back(id);
  }
};

template <class F>
class FnNode final : public Node {
 public:
  explicit FnNode(F f) : f_(std::move(f)) {}
  void run(RunContext& ctx) const override { f_(ctx); }

 private:
  F f_;
};

template <class F>
std::unique_ptr<Node> make_fn_node(F f) {
  return std::make_unique<FnNode<F>>(std::move(f));
}

inline PortSpec scalar_port(const std::string& name, bool required = true) {
  return {name, "kg.Scalar", required, "a number"};
}

// Registers every test node type into `r`. `journal` and `rendezvous` may be null.
inline void register_test_nodes(Registry& r, std::shared_ptr<Journal> journal = {},
                                std::shared_ptr<Rendezvous> rendezvous = {}) {
  auto note = [journal](const RunContext& ctx) {
    if (journal) journal->add(ctx.node_id());
  };

  {
    NodeSpec s{"test.constant", 1, "Outputs its value.", {}, {scalar_port("out")}, {}};
    s.params.push_back({"value", ParamType::Float, 0.0, "the number"});
    r.add_node({s, [note](const Params& p) {
                  const double v = p.get<double>("value");
                  return make_fn_node([v, note](RunContext& ctx) {
                    note(ctx);
                    ctx.output("out", v);
                  });
                }});
  }
  {
    NodeSpec s{"test.add",
               1,
               "a + b (b optional, 0 when absent).",
               {scalar_port("a"), scalar_port("b", false)},
               {scalar_port("sum")},
               {}};
    r.add_node({s, [note](const Params&) {
                  return make_fn_node([note](RunContext& ctx) {
                    note(ctx);
                    const double b = ctx.has_input("b") ? ctx.input<double>("b") : 0.0;
                    ctx.output("sum", ctx.input<double>("a") + b);
                    ctx.report("b_connected", ctx.has_input("b"));
                  });
                }});
  }
  {
    NodeSpec s{"test.scale", 1, "in * factor.", {scalar_port("in")}, {scalar_port("out")}, {}};
    ParamSpec factor{"factor", ParamType::Float, 1.0, "multiplier"};
    factor.min = -10.0;
    factor.max = 10.0;
    s.params.push_back(factor);
    r.add_node({s, [note](const Params& p) {
                  const double f = p.get<double>("factor");
                  return make_fn_node([f, note](RunContext& ctx) {
                    note(ctx);
                    ctx.output("out", ctx.input<double>("in") * f);
                    ctx.report("factor", f);
                  });
                }});
  }
  {
    NodeSpec s{"test.fail", 1, "Throws its message.", {scalar_port("in", false)}, {scalar_port("out")}, {}};
    s.params.push_back({"message", ParamType::String, std::string("deliberate failure"), "what to throw"});
    r.add_node({s, [note](const Params& p) {
                  const std::string m = p.get<std::string>("message");
                  return make_fn_node([m, note](RunContext& ctx) {
                    note(ctx);
                    ctx.log("about to fail");
                    throw std::runtime_error(m);
                  });
                }});
  }
  {
    NodeSpec s{"test.silent", 1, "Declares an output and never sets it.", {}, {scalar_port("out")}, {}};
    r.add_node({s, [note](const Params&) { return make_fn_node([note](RunContext& ctx) { note(ctx); }); }});
  }
  {
    NodeSpec s{"test.wrong_type", 1, "Sets a kg.String on a kg.Scalar output.", {}, {scalar_port("out")}, {}};
    r.add_node({s, [](const Params&) {
                  return make_fn_node(
                      [](RunContext& ctx) { ctx.output("out", std::string("not a number")); });
                }});
  }
  {
    NodeSpec s{"test.undeclared_input", 1, "Reads an input its spec lacks.", {}, {scalar_port("out")}, {}};
    r.add_node({s, [](const Params&) {
                  return make_fn_node([](RunContext& ctx) { ctx.output("out", ctx.input<double>("ghost")); });
                }});
  }
  {
    NodeSpec s{"test.motion_source",
               1,
               "Outputs a port of another type.",
               {},
               {{"motion", "kg.Motion", true, ""}},
               {}};
    r.add_node({s, [](const Params&) { return make_fn_node([](RunContext&) {}); }});
  }
  {
    NodeSpec s{"test.figures", 1, "Reports one figure of each kind.", {}, {scalar_port("out")}, {}};
    r.add_node({s, [](const Params&) {
                  return make_fn_node([](RunContext& ctx) {
                    ctx.report("iterations", std::int64_t{42});
                    ctx.report("residual", 0.125);
                    ctx.report("converged", true);
                    ctx.report("note", std::string("tab\there \"quoted\""));
                    ctx.report("iterations", std::int64_t{43});  // replaces, keeps its place
                    ctx.log("reported");
                    ctx.output("out", 1.0);
                  });
                }});
  }
  {
    NodeSpec s{"test.meet",
               1,
               "Waits for another test.meet node (rendezvous) up to timeout_ms.",
               {scalar_port("in", false)},
               {{"met", "kg.Bool", true, ""}},
               {}};
    ParamSpec t{"timeout_ms", ParamType::Int, std::int64_t{5000}, "how long to wait"};
    t.min = 0;
    s.params.push_back(t);
    s.side_effects = true;  // meets another node outside the run's values: never merged
    r.add_node({s, [rendezvous, note](const Params& p) {
                  const auto ms = std::chrono::milliseconds(p.get<std::int64_t>("timeout_ms"));
                  return make_fn_node([rendezvous, ms, note](RunContext& ctx) {
                    note(ctx);
                    if (!rendezvous) throw std::runtime_error("no rendezvous given to this registry");
                    ctx.output("met", rendezvous->meet(ms));
                  });
                }});
  }
  {
    NodeSpec s{"test.sleep",         1, "Sleeps, then outputs in + 1.", {scalar_port("in", false)},
               {scalar_port("out")}, {}};
    ParamSpec ms{"ms", ParamType::Int, std::int64_t{10}, "milliseconds"};
    ms.min = 0;
    ms.max = 10000;
    s.params.push_back(ms);
    s.side_effects = true;  // its wall time is what the tests observe: never merged
    r.add_node({s, [note](const Params& p) {
                  const auto d = std::chrono::milliseconds(p.get<std::int64_t>("ms"));
                  return make_fn_node([d, note](RunContext& ctx) {
                    std::this_thread::sleep_for(d);
                    note(ctx);
                    ctx.output("out", (ctx.has_input("in") ? ctx.input<double>("in") : 0.0) + 1.0);
                  });
                }});
  }
  {
    NodeSpec s{"test.bad_factory",   1, "Its factory refuses a combination of params.", {},
               {scalar_port("out")}, {}};
    s.params.push_back({"lo", ParamType::Float, 0.0, ""});
    s.params.push_back({"hi", ParamType::Float, 1.0, ""});
    r.add_node({s, [](const Params& p) -> std::unique_ptr<Node> {
                  if (p.get<double>("lo") > p.get<double>("hi"))
                    throw std::invalid_argument("lo must not exceed hi");
                  return make_fn_node([](RunContext& ctx) { ctx.output("out", 0.0); });
                }});
  }
  {
    // One param of every type, to test coercion.
    NodeSpec s{"test.params", 1, "Takes every kind of param.", {}, {scalar_port("out")}, {}};
    s.params.push_back({"flag", ParamType::Bool, false, "a bool"});
    ParamSpec count{"count", ParamType::Int, std::int64_t{3}, "an int in [0, 100]"};
    count.min = 0;
    count.max = 100;
    s.params.push_back(count);
    ParamSpec ratio{"ratio", ParamType::Float, 0.5, "a float in [0, 1]"};
    ratio.min = 0.0;
    ratio.max = 1.0;
    s.params.push_back(ratio);
    s.params.push_back({"name", ParamType::String, std::string("anon"), "a string"});
    ParamSpec mode{"mode", ParamType::Enum, std::string("fast"), "an enum"};
    mode.choices = {"fast", "slow", "exact"};
    s.params.push_back(mode);
    s.params.push_back({"src", ParamType::InputPath, std::string(), "a file read"});
    s.params.push_back({"dst", ParamType::OutputPath, std::string(), "a file written"});
    ParamSpec list{"gravity", ParamType::FloatList, std::vector<double>{0, -9.81, 0}, "a list in [-20, 20]"};
    list.min = -20.0;
    list.max = 20.0;
    s.params.push_back(list);
    r.add_node(
        {s, [](const Params&) { return make_fn_node([](RunContext& ctx) { ctx.output("out", 0.0); }); }});
  }
  {
    NodeSpec s{"test.needs", 1, "Has a required param.", {}, {scalar_port("out")}, {}};
    s.params.push_back({"path", ParamType::InputPath, std::string(), "the file to read", true});
    r.add_node(
        {s, [](const Params&) { return make_fn_node([](RunContext& ctx) { ctx.output("out", 0.0); }); }});
  }
}

inline Registry test_registry(std::shared_ptr<Journal> journal = {},
                              std::shared_ptr<Rendezvous> rendezvous = {}) {
  Registry r;
  register_test_nodes(r, std::move(journal), std::move(rendezvous));
  return r;
}

}  // namespace kg_test

// Two interfaces for the extension tests: an extension of one is never handed out as the other.
namespace kg_test {
struct TestAnswer {
  double value = 0;
};
struct TestQuestion {
  std::string text;
};
}  // namespace kg_test
KG_DECLARE_INTERFACE(kg_test::TestAnswer, "kg.TestAnswer")
KG_DECLARE_INTERFACE(kg_test::TestQuestion, "kg.TestQuestion")
