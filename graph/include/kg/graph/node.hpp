// A node type: its spec and a factory making configured nodes. A node is built once per graph
// from its checked params and keeps no per-run state: run() is const and may run concurrently
// for several runs (DESIGN.md 1). Everything of one run goes through the RunContext.
//
//   class Scale final : public Node {
//    public:
//     explicit Scale(const Params& p) : factor_(p.get<double>("factor")) {}
//     void run(RunContext& ctx) const override {
//       ctx.set_output("out", Value::make(ctx.input<double>("in") * factor_));
//       ctx.report("factor", factor_);
//     }
//    private:
//     double factor_;
//   };
//   registry.add_node({spec, [](const Params& p) { return std::make_unique<Scale>(p); }});
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <variant>

#include "kg/graph/extension.hpp"
#include "kg/graph/node_spec.hpp"
#include "kg/graph/params.hpp"
#include "kg/graph/value.hpp"

namespace kg::graph {

// A figure a node reports for --report (iterations, worst violation, frames read, ...).
using Figure = std::variant<bool, std::int64_t, double, std::string>;

class RunContext {
 public:
  virtual ~RunContext() = default;

  virtual const std::string& node_id() const = 0;
  virtual const Params& params() const = 0;

  // The value on an input port; an empty Value when an optional input is not connected.
  virtual const Value& input_value(const std::string& port) const = 0;
  virtual void set_output(const std::string& port, Value value) = 0;
  virtual void report(const std::string& key, Figure value) = 0;
  // A line for the user (stderr, prefixed with the node id).
  virtual void log(const std::string& message) = 0;

  // The registry extension `name` of interface T (extension.hpp), e.g. a constraint kind a solver
  // node meets in its input data; null when absent or when the context has no registry.
  template <Interface T>
  std::shared_ptr<const T> find(const std::string& name) const {
    return std::static_pointer_cast<const T>(find_extension(InterfaceName<T>::value, name));
  }

  // The type-erased layer under find<T> that contexts implement by forwarding to their
  // registry's find_extension (which guards the interface); nodes call find<T>.
  virtual std::shared_ptr<const void> find_extension(const std::string& interface,
                                                     const std::string& name) const {
    return nullptr;
  }

  // True when the run's files must come out byte for byte the same every time (batch runs,
  // `run --reproducible`): a node then leaves wall-clock times out of the files it writes and
  // reports them as figures only.
  virtual bool reproducible() const { return false; }

  bool has_input(const std::string& port) const { return !input_value(port).empty(); }

  template <Named T>
  const T& input(const std::string& port) const {
    return input_value(port).get<T>();
  }
  template <Named T>
  void output(const std::string& port, T value) {
    set_output(port, Value::make(std::move(value)));
  }
};

class Node {
 public:
  virtual ~Node() = default;
  // Throws on failure; the executor reports the message with the node id.
  virtual void run(RunContext& ctx) const = 0;
};

// Builds a node from checked params (defaults filled in). May throw std::exception for a
// combination of params the spec cannot express; the loader reports it with the node's place.
using NodeFactory = std::function<std::unique_ptr<Node>(const Params&)>;

// The same for a node that picks one of the registry's extensions by its params when it is made
// (io.export_motion: the kg.MotionFormat claiming its path's extension), so that a missing one
// fails at load, at the node's place. `registry` is the one making the node (not owned): keep
// what find<T> hands out, never the registry.
using RegistryNodeFactory = std::function<std::unique_ptr<Node>(const Params&, const Registry&)>;

struct NodeType {
  NodeSpec spec;
  NodeFactory create;
  RegistryNodeFactory create_with_registry{};  // when set, used instead of `create`
};

}  // namespace kg::graph
