// Small node types for the CLI and executor tests, loaded at run time from KG_TEST_PLUGIN_DIR
// (kg_test_nodes.so). They move kg.Scalar values around, fail on purpose, write files and check
// that branches really run in parallel.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "kg/base/atomic_file.hpp"
#include "kg/graph/plugin_abi.hpp"

namespace {

using kg::graph::NodeSpec;
using kg::graph::NodeType;
using kg::graph::Params;
using kg::graph::ParamType;
using kg::graph::RunContext;

class Constant final : public kg::graph::Node {
 public:
  explicit Constant(const Params& p) : value_(p.get<double>("value")) {}
  void run(RunContext& ctx) const override {
    ctx.output("value", value_);
    ctx.report("value", value_);
  }

 private:
  double value_;
};

class Add final : public kg::graph::Node {
 public:
  explicit Add(const Params&) {}
  void run(RunContext& ctx) const override {
    const double sum = ctx.input<double>("a") + (ctx.has_input("b") ? ctx.input<double>("b") : 0.0);
    ctx.output("sum", sum);
    ctx.report("sum", sum);
  }
};

class Fail final : public kg::graph::Node {
 public:
  explicit Fail(const Params& p) : message_(p.get<std::string>("message")) {}
  void run(RunContext&) const override { throw std::runtime_error(message_); }

 private:
  std::string message_;
};

class Print final : public kg::graph::Node {
 public:
  explicit Print(const Params& p)
      : path_(p.get<std::string>("path")), write_seconds_(p.get<double>("write_seconds")) {}
  void run(RunContext& ctx) const override {
    const double value = ctx.input<double>("value");
    char text[64];
    std::snprintf(text, sizeof text, "%.17g\n", value);
    kg::write_file_atomically(path_, [&](std::ostream& os) {
      os << text[0] << std::flush;  // what an interrupted write would leave behind
      std::this_thread::sleep_for(std::chrono::duration<double>(write_seconds_));
      os << text + 1;
    });
    ctx.log("wrote " + path_);
  }

 private:
  std::string path_;
  double write_seconds_;
};

// Reads a number from a text file (batch tests): "abort" aborts the process, as a crashing node
// would; anything else not a number fails the node.
class ReadNumber final : public kg::graph::Node {
 public:
  explicit ReadNumber(const Params& p) : path_(p.get<std::string>("path")) {}
  void run(RunContext& ctx) const override {
    const std::string text = kg::read_input_file(path_, "number file");
    if (text.rfind("abort", 0) == 0) std::abort();
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0) throw std::runtime_error(path_ + ": expected a number, got '" + text + "'");
    ctx.output("value", value);
    ctx.report("value", value);
  }

 private:
  std::string path_;
};

// Waits until `count` nodes of its group have arrived, so a graph of `count` rendezvous nodes
// succeeds only when they run at the same time (--jobs >= count).
class Rendezvous final : public kg::graph::Node {
 public:
  explicit Rendezvous(const Params& p)
      : group_(p.get<std::string>("group")),
        count_(p.get<std::int64_t>("count")),
        timeout_(p.get<double>("timeout_seconds")) {}
  void run(RunContext& ctx) const override {
    static std::mutex mutex;
    static std::condition_variable arrived;
    static std::map<std::string, std::int64_t> arrivals;
    std::unique_lock lock(mutex);
    const std::int64_t target = (arrivals[group_] / count_ + 1) * count_;
    ++arrivals[group_];
    arrived.notify_all();
    if (!arrived.wait_for(lock, std::chrono::duration<double>(timeout_),
                          [&] { return arrivals[group_] >= target; })) {
      arrivals[group_] = target;  // let the next run of the group start afresh
      throw std::runtime_error("rendezvous " + group_ +
                               " timed out: the other nodes did not run in parallel");
    }
    ctx.output("value", ctx.has_input("in") ? ctx.input<double>("in") : 0.0);
  }

 private:
  std::string group_;
  std::int64_t count_;
  double timeout_;
};

template <class N>
NodeType type(NodeSpec spec) {
  return {std::move(spec), [](const Params& p) { return std::make_unique<N>(p); }};
}

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord r{"kg.test_nodes", "1.0.0"};
  r.nodes.push_back(type<Constant>({"test.constant",
                                    1,
                                    "Outputs a number.",
                                    {},
                                    {{"value", "kg.Scalar", true, "the number"}},
                                    {{.name = "value",
                                      .type = ParamType::Float,
                                      .default_value = 0.0,
                                      .doc = "the number to output",
                                      .min = -1e6,
                                      .max = 1e6}}}));
  r.nodes.push_back(type<Add>(
      {"test.add",
       1,
       "Adds two numbers.",
       {{"a", "kg.Scalar", true, "first term"}, {"b", "kg.Scalar", false, "second term, 0 when absent"}},
       {{"sum", "kg.Scalar", true, "a + b"}},
       {}}));
  r.nodes.push_back(type<Fail>({"test.fail",
                                1,
                                "Always fails with its message.",
                                {{"in", "kg.Scalar", false, "ignored"}},
                                {{"value", "kg.Scalar", true, "never set"}},
                                {{.name = "message",
                                  .type = ParamType::String,
                                  .default_value = std::string("deliberate failure"),
                                  .doc = "the failure's message"}}}));
  r.nodes.push_back(type<Print>({"test.print",
                                 1,
                                 "Writes a number to a text file.",
                                 {{"value", "kg.Scalar", true, "the number"}},
                                 {},
                                 {{.name = "path",
                                   .type = ParamType::OutputPath,
                                   .default_value = std::string(),
                                   .doc = "the file to write",
                                   .required = true},
                                  {.name = "write_seconds",
                                   .type = ParamType::Float,
                                   .default_value = 0.0,
                                   .doc = "seconds the write takes (the file half written meanwhile)",
                                   .min = 0.0}}}));
  r.nodes.push_back(type<ReadNumber>({"test.read_number",
                                      1,
                                      "Reads a number from a text file.",
                                      {},
                                      {{"value", "kg.Scalar", true, "the number"}},
                                      {{.name = "path",
                                        .type = ParamType::InputPath,
                                        .default_value = std::string(),
                                        .doc = "the file to read",
                                        .required = true}}}));
  r.nodes.push_back(type<Rendezvous>(
      {"test.rendezvous",
       1,
       "Succeeds only when `count` nodes of its group run at once.",
       {{"in", "kg.Scalar", false, "passed through"}},
       {{"value", "kg.Scalar", true, "in, or 0"}},
       {{.name = "group", .type = ParamType::String, .default_value = std::string("g"), .doc = "group name"},
        {.name = "count",
         .type = ParamType::Int,
         .default_value = std::int64_t{2},
         .doc = "nodes that must meet",
         .min = 1.0},
        {.name = "timeout_seconds",
         .type = ParamType::Float,
         .default_value = 5.0,
         .doc = "seconds to wait",
         .min = 0.0}}}));
  r.nodes.back().spec.side_effects = true;  // meets other nodes outside the run's values: never merged
  return r;
}

}  // namespace

KG_PLUGIN(make_record)
