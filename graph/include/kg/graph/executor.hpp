// Runs a loaded Graph. Each run owns its values (the Graph is never modified); nodes run in a
// topological order, independent branches in parallel on up to `jobs` threads. A node that
// throws is reported with its id and message; nodes downstream of it are skipped; the others
// still run.
//
// The executor owns caching and effects (DESIGN.md 13). Each node gets a key: the SHA-256 of its
// type, type version, params (canonical text) and, per input port, the key of the node producing
// it and that output's name, computed in topological order. Nodes of one run with the same key
// compute once: the later one does not run, takes the first's outputs and figures (its failure
// too, with the same message), and its NodeRun says same_as the first (as Gaffer hashes plugs to
// cache). Nodes whose spec declares side_effects (sinks: exporters, file writers) always run.
// Each produced value is dropped by the executor once every consumer of that output has run,
// unless RunOptions::keep_outputs keeps it for RunResult::outputs.
//
//   RunResult result = run_graph(graph, registry, {.jobs = 2});
//   write_report_json("report.json", graph, result);
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "kg/graph/graph.hpp"
#include "kg/graph/node.hpp"

namespace kg::graph {

enum class NodeStatus { Ok, Failed, Skipped };
const char* to_string(NodeStatus status);

struct NodeRun {
  std::string id;
  std::string type;
  NodeStatus status = NodeStatus::Skipped;
  std::string message;  // the failure's message, or which failed node caused the skip
  std::string same_as;  // the node of the run with the same key whose results this one took; "" when it ran
  std::string key;      // the node's key (64 hex digits)
  double wall_seconds = 0;
  std::vector<std::pair<std::string, Figure>> figures;  // in the order reported
};

struct RunResult {
  bool ok = true;  // every node Ok
  double wall_seconds = 0;
  std::vector<NodeRun> nodes;  // in the graph's node order
  // With RunOptions::keep_outputs: values of every output port of nodes that ran (or took
  // another's results), keyed "node.port" (for tests and tools). Empty otherwise.
  std::map<std::string, Value> outputs;
};

struct RunOptions {
  int jobs = 1;               // threads; values < 1 mean 1
  bool reproducible = false;  // RunContext::reproducible
  // Keep every output in RunResult::outputs (tests, tools). false: each value is freed once its
  // last consumer has run (the CLI and batch items, which need only the files sinks write).
  bool keep_outputs = true;
  // Called with (node id, message) for node log lines and failures; default prints to stderr.
  std::function<void(const std::string&, const std::string&)> on_log{};
  // Every setting is valid (jobs < 1 means 1): here so that every Options struct has its
  // validate() (DESIGN.md 15); a future field with a range checks it here.
  void validate() const {}
};

RunResult run_graph(const Graph& graph, const Registry& registry, const RunOptions& options = {});

// {"graph": ..., "ok": ..., "wall_seconds": ..., "nodes": [{"id","type","status","message",
//  "same_as" (only for a node that took another's results),"wall_seconds","figures":{...}}]},
// written atomically.
void write_report_json(const std::filesystem::path& file, const Graph& graph, const RunResult& result);

}  // namespace kg::graph
