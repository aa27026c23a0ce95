// Test support: running one node by hand, outside any graph. The test sets the inputs, the node
// runs once, and its outputs, figures and log lines stay in the context for the checks. Only
// kg/graph headers: graph/ tests may use it without depending on nodes/.
//
//   const graph::Registry registry = registry_of(kg::motion_node_types());
//   NodeContext ctx = run_node(registry, "motion.resample", params_for(registry, "motion.resample",
//                              {{"fps", 30.0}}), {{"motion", graph::Value::make(clip)}});
//   CHECK(std::get<std::int64_t>(ctx.figures.at("frames_out")) == 61);
#pragma once

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"

namespace kg::test {

// A RunContext whose inputs the test sets and whose outputs, figures and logs it reads.
class NodeContext final : public graph::RunContext {
 public:
  // `params` is what params() answers; nodes are built from theirs, so it rarely matters.
  explicit NodeContext(graph::Params params = {}) : params_(std::move(params)) {}

  const std::string& node_id() const override { return id_; }
  const graph::Params& params() const override { return params_; }
  const graph::Value& input_value(const std::string& port) const override {
    static const graph::Value none;
    auto it = inputs.find(port);
    return it == inputs.end() ? none : it->second;
  }
  void set_output(const std::string& port, graph::Value value) override { outputs[port] = std::move(value); }
  void report(const std::string& key, graph::Figure value) override { figures[key] = std::move(value); }
  void log(const std::string& message) override { logs.push_back(message); }
  std::shared_ptr<const void> find_extension(const std::string& interface,
                                             const std::string& name) const override {
    return registry ? registry->find_extension(interface, name) : nullptr;
  }

  // Whether some logged line contains `part`.
  bool logged(const std::string& part) const {
    for (const std::string& line : logs)
      if (line.find(part) != std::string::npos) return true;
    return false;
  }

  std::map<std::string, graph::Value> inputs;  // unset ports read as not connected
  std::map<std::string, graph::Value> outputs;
  std::map<std::string, graph::Figure> figures;
  std::vector<std::string> logs;
  // Where find_extension looks (not owned; null: nowhere). run_node(registry, ...) sets it.
  const graph::Registry* registry = nullptr;

 private:
  std::string id_ = "node";
  graph::Params params_;
};

// A registry holding `types` (a list such as kg::bvh_node_types()) as built-ins, through the
// same add_node as every module, so each spec is checked and its defaults normalised.
inline graph::Registry registry_of(std::vector<graph::NodeType> types) {
  graph::Registry registry;
  for (graph::NodeType& type : types) registry.add_node(std::move(type));
  return registry;
}

// The registered type `name`; throws std::runtime_error naming it when absent.
inline const graph::NodeType& node_type(const graph::Registry& registry, const std::string& name) {
  const graph::NodeType* type = registry.find_node(name);
  if (type == nullptr) throw std::runtime_error("node type " + name + " not registered");
  return *type;
}

// The spec's defaults (required params left unset) with `given` on top, as the graph loader
// fills them in.
inline graph::Params params_for(const graph::NodeSpec& spec,
                                const std::map<std::string, graph::ParamValue>& given = {}) {
  graph::Params params;
  for (const graph::ParamSpec& p : spec.params)
    if (!p.required) params.set(p.name, p.default_value);
  for (const auto& [name, value] : given) params.set(name, value);
  return params;
}
inline graph::Params params_for(const graph::Registry& registry, const std::string& type,
                                const std::map<std::string, graph::ParamValue>& given = {}) {
  return params_for(node_type(registry, type).spec, given);
}

// Builds a node of `type` from `params` and runs it once on `inputs`; what creating or running
// throws propagates. The context returned holds the outputs, figures and log lines.
inline NodeContext run_node(const graph::NodeType& type, const graph::Params& params,
                            std::map<std::string, graph::Value> inputs = {}) {
  if (!type.create)
    throw std::logic_error(
        "node type " + type.spec.type +
        " is made from a registry (create_with_registry): " + "run it with run_node(registry, ...)");
  NodeContext ctx(params);
  ctx.inputs = std::move(inputs);
  type.create(params)->run(ctx);
  return ctx;
}
// The same through Registry::create_node, which keeps a plugin's library loaded while it runs
// and gives node types made from a registry theirs; the node finds the registry's extensions.
inline NodeContext run_node(const graph::Registry& registry, const std::string& type,
                            const graph::Params& params, std::map<std::string, graph::Value> inputs = {}) {
  NodeContext ctx(params);
  ctx.inputs = std::move(inputs);
  ctx.registry = &registry;
  registry.create_node(type, params)->run(ctx);
  return ctx;
}

}  // namespace kg::test
