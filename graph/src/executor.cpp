#include "kg/graph/executor.hpp"

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <iostream>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "kg/base/atomic_file.hpp"
#include "kg/base/json.hpp"
#include "kg/graph/sha256.hpp"

namespace kg::graph {

const char* to_string(NodeStatus status) {
  switch (status) {
    case NodeStatus::Ok:
      return "ok";
    case NodeStatus::Failed:
      return "failed";
    case NodeStatus::Skipped:
      return "skipped";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;
using LogFn = std::function<void(const std::string&, const std::string&)>;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string port_names(const std::vector<PortSpec>& ports) {
  std::string s;
  for (const PortSpec& p : ports) s += (s.empty() ? "" : ", ") + p.name;
  return s.empty() ? "none" : s;
}

// One node's view of one run: its inputs (read-only, shared with other consumers) and what it
// produces. Lives on the worker's stack while the node runs.
class Context final : public RunContext {
 public:
  Context(const NodeInstance& node, const NodeSpec& spec, std::map<std::string, Value> inputs,
          std::shared_ptr<const void> owner, const LogFn& log, const Registry& registry, bool reproducible)
      : node_(node),
        spec_(spec),
        inputs_(std::move(inputs)),
        owner_(std::move(owner)),
        log_(log),
        registry_(registry),
        reproducible_(reproducible) {}

  bool reproducible() const override { return reproducible_; }

  const std::string& node_id() const override { return node_.id; }
  const Params& params() const override { return node_.params; }

  const Value& input_value(const std::string& port) const override {
    static const Value none;
    if (!spec_.find_input(port))
      throw Error("node '" + node_.id + "' (" + node_.type + ") read input '" + port +
                  "', which its type does not declare (inputs: " + port_names(spec_.inputs) + ")");
    auto it = inputs_.find(port);
    return it == inputs_.end() ? none : it->second;
  }

  void set_output(const std::string& port, Value value) override {
    const PortSpec* out = spec_.find_output(port);
    if (!out)
      throw Error("node '" + node_.id + "' (" + node_.type + ") set output '" + port +
                  "', which its type does not declare (outputs: " + port_names(spec_.outputs) + ")");
    if (value.empty()) throw Error("node '" + node_.id + "' set output '" + port + "' to an empty value");
    if (value.type_name() != out->type)
      throw Error("output " + node_.id + "." + port + " is declared " + out->type + ", but the node set a " +
                  value.type_name());
    outputs_[port] = owner_ ? value.kept_alive_by(owner_) : std::move(value);
  }

  void report(const std::string& key, Figure value) override {
    for (auto& [k, v] : figures_)
      if (k == key) {
        v = std::move(value);
        return;
      }
    figures_.emplace_back(key, std::move(value));
  }

  void log(const std::string& message) override { log_(node_.id, message); }

  // The run's registry: built-in and plugin extensions alike (a plugin's constraint kinds reach
  // the solver nodes this way).
  std::shared_ptr<const void> find_extension(const std::string& interface,
                                             const std::string& name) const override {
    return registry_.find_extension(interface, name);
  }

  std::map<std::string, Value>& outputs() { return outputs_; }
  std::vector<std::pair<std::string, Figure>>& figures() { return figures_; }

 private:
  const NodeInstance& node_;
  const NodeSpec& spec_;
  std::map<std::string, Value> inputs_;
  std::shared_ptr<const void> owner_;
  const LogFn& log_;
  const Registry& registry_;
  bool reproducible_;
  std::map<std::string, Value> outputs_;
  std::vector<std::pair<std::string, Figure>> figures_;
};

struct Input {
  std::string port;
  std::size_t from;
  std::string from_port;
};

// The node's key: SHA-256 of its type, the type's version, its params (canonical text, by name)
// and, per input port, the key of its producer and that producer's output port. Producers' keys
// must be known (topological order). Two nodes with the same key compute the same thing.
std::string node_key(const NodeInstance& node, const NodeType* type, const std::vector<Input>& inputs,
                     const std::vector<std::string>& keys) {
  std::string text = "kg.node-key 1\ntype " + node.type + "\nversion " +
                     (type ? std::to_string(type->spec.version) : std::string("?")) + "\n";
  for (const auto& [name, value] : node.params.all())
    text += "param " + name + " = " + to_string(value) + "\n";
  std::vector<std::string> wired;
  for (const Input& in : inputs)
    wired.push_back("input " + in.port + " <- " + keys[in.from] + "." + in.from_port + "\n");
  std::sort(wired.begin(), wired.end());
  for (const std::string& line : wired) text += line;
  return sha256_hex(text);
}

}  // namespace

RunResult run_graph(const Graph& graph, const Registry& registry, const RunOptions& options) {
  options.validate();
  const auto t0 = Clock::now();
  const std::size_t n = graph.nodes.size();

  std::vector<std::vector<std::size_t>> downstream(n);
  std::vector<std::vector<Input>> inputs(n);
  std::vector<std::size_t> pending(n, 0);
  const std::vector<std::pair<std::size_t, std::size_t>> ends = graph.connection_ends();
  // Per node and output port: how many consumers have still to take the value (connections, and
  // nodes taking all of this node's results), so that it can be freed after the last.
  std::vector<std::map<std::string, std::size_t>> consumers(n);
  for (std::size_t k = 0; k < ends.size(); ++k) {
    const auto [from, to] = ends[k];
    const Connection& c = graph.connections[k];
    downstream[from].push_back(to);
    inputs[to].push_back({c.to.port, from, c.from.port});
    ++consumers[from][c.from.port];
    ++pending[to];
  }
  // Throws for a cycle, which would otherwise never finish.
  const std::vector<std::size_t> order = graph.topological_order();

  RunResult result;
  result.nodes.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    result.nodes[i].id = graph.nodes[i].id;
    result.nodes[i].type = graph.nodes[i].type;
  }

  // Keys in topological order; the first node (in that order) of each key computes, the others
  // with that key wait for it (an extra dependency) and take its results.
  std::vector<std::string> keys(n);
  std::vector<std::size_t> first_of(n);
  std::vector<std::vector<std::size_t>> duplicates(n);
  {
    std::map<std::string, std::size_t> first_with_key;
    for (std::size_t i : order) {
      const NodeType* type = registry.find_node(graph.nodes[i].type);
      keys[i] = node_key(graph.nodes[i], type, inputs[i], keys);
      result.nodes[i].key = keys[i];
      first_of[i] = i;
      if (type && type->spec.has_side_effects()) continue;
      auto [it, fresh] = first_with_key.emplace(keys[i], i);
      if (fresh) continue;
      // Not upstream of i: a node's key covers its producers' keys, so an upstream node has
      // another key. The edge can make no cycle.
      first_of[i] = it->second;
      duplicates[it->second].push_back(i);
      downstream[it->second].push_back(i);
      ++pending[i];
    }
    for (std::size_t i = 0; i < n; ++i)
      if (!duplicates[i].empty()) {
        const NodeType* type = registry.find_node(graph.nodes[i].type);
        if (type)
          for (const PortSpec& out : type->spec.outputs) consumers[i][out.name] += duplicates[i].size();
      }
  }

  std::mutex log_mutex;
  const LogFn log = [&](const std::string& id, const std::string& message) {
    std::lock_guard<std::mutex> lock(log_mutex);
    if (!options.on_log) {
      std::cerr << '[' << id << "] " << message << '\n';
      return;
    }
    // A throwing log callback must not take a worker thread (and the process) down.
    try {
      options.on_log(id, message);
    } catch (const std::exception& e) {
      std::cerr << '[' << id << "] " << message << " (log callback failed: " << e.what() << ")\n";
    } catch (...) {
      std::cerr << '[' << id << "] " << message << " (log callback failed)\n";
    }
  };

  std::vector<std::map<std::string, Value>> produced(n);
  std::vector<std::vector<std::string>> failed_upstream(n);  // the failed nodes that make a node skip

  std::mutex mutex;
  std::condition_variable changed;
  std::set<std::size_t> ready;  // ordered: file order among ready nodes
  std::size_t finished = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (pending[i] == 0) ready.insert(i);

  // Under the lock: one consumer of node i's output `port` is done with it; the last frees it.
  auto consumed = [&](std::size_t i, const std::string& port) {
    auto it = consumers[i].find(port);
    if (it == consumers[i].end() || it->second == 0) return;
    if (--it->second == 0 && !options.keep_outputs) produced[i].erase(port);
  };
  // Under the lock, once node i has finished: outputs no one consumes are freed at once.
  auto drop_unconsumed = [&](std::size_t i) {
    if (options.keep_outputs) return;
    for (auto it = produced[i].begin(); it != produced[i].end();) {
      auto c = consumers[i].find(it->first);
      it = (c == consumers[i].end() || c->second == 0) ? produced[i].erase(it) : std::next(it);
    }
  };

  // Runs node i outside the lock. Only this worker touches result.nodes[i] and produced[i]
  // meanwhile.
  auto execute = [&](std::size_t i, std::map<std::string, Value> values) {
    const NodeInstance& inst = graph.nodes[i];
    NodeRun& run = result.nodes[i];
    const NodeType* type = registry.find_node(inst.type);
    if (!type) {
      run.status = NodeStatus::Failed;
      run.message = "node type '" + inst.type + "' is not registered";
      return;
    }
    const auto start = Clock::now();
    std::optional<Context> ctx;
    try {
      NodePtr node = inst.node ? inst.node : registry.create_node(inst.type, inst.params);
      ctx.emplace(inst, type->spec, std::move(values), registry.node_owner(inst.type), log, registry,
                  options.reproducible);
      node->run(*ctx);
      produced[i] = std::move(ctx->outputs());
      run.figures = std::move(ctx->figures());
      run.status = NodeStatus::Ok;
    } catch (const std::exception& e) {
      run.status = NodeStatus::Failed;
      run.message = e.what();
    } catch (...) {
      run.status = NodeStatus::Failed;
      run.message = "unknown exception (not derived from std::exception)";
    }
    if (run.status == NodeStatus::Failed && ctx) {
      // The outputs its spec keeps on failure (a report saying why).
      for (auto& [port, value] : ctx->outputs()) {
        const PortSpec* out = type->spec.find_output(port);
        if (out && out->kept_on_failure) produced[i][port] = std::move(value);
      }
    }
    ctx.reset();  // the inputs go before the time is taken
    run.wall_seconds = seconds_since(start);
  };

  auto worker = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      changed.wait(lock, [&] { return !ready.empty() || finished == n; });
      if (ready.empty()) return;
      const std::size_t i = *ready.begin();
      ready.erase(ready.begin());
      NodeRun& run = result.nodes[i];

      // Upstream results are final once a node is ready: decide here whether it can run.
      std::vector<std::string>& causes = failed_upstream[i];
      std::map<std::string, Value> values;
      std::string missing;
      for (const Input& in : inputs[i]) {
        const NodeRun& up = result.nodes[in.from];
        auto it = produced[in.from].find(in.from_port);
        const bool delivered = it != produced[in.from].end();
        if (up.status == NodeStatus::Failed && !delivered) {  // a failed node's report is delivered
          causes.push_back(up.id);
        } else if (up.status == NodeStatus::Skipped) {
          causes.insert(causes.end(), failed_upstream[in.from].begin(), failed_upstream[in.from].end());
        } else if (delivered) {
          values[in.port] = it->second;
        } else if (missing.empty()) {
          missing = "input " + graph.nodes[i].id + "." + in.port + " not produced by " + up.id + "." +
                    in.from_port + " (node '" + up.id + "' ran but did not set that output)";
        }
        consumed(in.from, in.from_port);
      }
      const std::size_t first = first_of[i];
      if (!causes.empty()) {
        std::vector<std::string> unique;
        for (const std::string& c : causes)
          if (std::find(unique.begin(), unique.end(), c) == unique.end()) unique.push_back(c);
        causes = unique;
        run.status = NodeStatus::Skipped;
        run.message = "not run: upstream node" + std::string(causes.size() > 1 ? "s" : "") + " ";
        for (std::size_t k = 0; k < causes.size(); ++k) run.message += (k ? ", '" : "'") + causes[k] + "'";
        run.message += " failed";
      } else if (!missing.empty()) {
        run.status = NodeStatus::Failed;
        run.message = missing;
        lock.unlock();
        log(run.id, "failed: " + missing);
        lock.lock();
      } else if (first != i && result.nodes[first].status != NodeStatus::Skipped) {
        // The same type, params and inputs as `first`, which has finished: its results.
        values.clear();
        const NodeRun& same = result.nodes[first];
        run.status = same.status;
        run.message = same.message;
        run.figures = same.figures;
        run.same_as = same.id;
        for (const auto& [port, value] : produced[first]) produced[i][port] = value;
        if (const NodeType* type = registry.find_node(graph.nodes[first].type))
          for (const PortSpec& out : type->spec.outputs) consumed(first, out.name);
        lock.unlock();
        log(run.id,
            "same_as: " + same.id + " (the same type, params and inputs: its results, not run again)");
        if (run.status == NodeStatus::Failed) log(run.id, "failed: " + run.message);
        lock.lock();
      } else {
        lock.unlock();
        execute(i, std::move(values));
        if (run.status == NodeStatus::Failed) log(run.id, "failed: " + run.message);
        lock.lock();
      }
      if (first != i && run.same_as.empty())  // skipped, or ran itself: `first` keeps nothing for it
        if (const NodeType* type = registry.find_node(graph.nodes[first].type))
          for (const PortSpec& out : type->spec.outputs) consumed(first, out.name);
      drop_unconsumed(i);
      ++finished;
      for (std::size_t j : downstream[i])
        if (--pending[j] == 0) ready.insert(j);
      changed.notify_all();
    }
  };

  const std::size_t threads =
      std::min<std::size_t>(static_cast<std::size_t>(std::max(1, options.jobs)), std::max<std::size_t>(1, n));
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error&) {
      break;  // fewer threads than asked: still correct, only slower
    }
  }
  worker();
  for (std::thread& t : pool) t.join();

  for (std::size_t i = 0; i < n; ++i) {
    if (result.nodes[i].status != NodeStatus::Ok) result.ok = false;
    if (result.nodes[i].status == NodeStatus::Skipped || !options.keep_outputs) continue;
    for (auto& [port, value] : produced[i]) result.outputs[graph.nodes[i].id + "." + port] = std::move(value);
  }
  result.wall_seconds = seconds_since(t0);
  return result;
}

void write_report_json(const std::filesystem::path& file, const Graph& graph, const RunResult& result) {
  write_file_atomically(file, [&](std::ostream& os) {
    JsonWriter w(os);
    w.begin_object();
    w.field("graph", graph.file.string());
    w.field("ok", result.ok);
    w.field("wall_seconds", result.wall_seconds);
    w.key("variables");
    w.begin_object();
    for (const auto& [name, value] : graph.values) w.field(name, value);
    w.end_object();
    w.key("nodes");
    w.begin_array();
    for (const NodeRun& run : result.nodes) {
      w.begin_object();
      w.field("id", run.id);
      w.field("type", run.type);
      w.field("status", to_string(run.status));
      w.field("message", run.message);
      w.field("same_as", run.same_as);
      w.field("wall_seconds", run.wall_seconds);
      w.key("figures");
      w.begin_object();
      for (const auto& [key, figure] : run.figures) w.field(key, figure);
      w.end_object();
      w.end_object();
    }
    w.end_array();
    w.end_object();
  });
}

}  // namespace kg::graph
