// Batch manifests: one JSON object per line, one line per finished item, appended as items finish
// (a single write per line, so a manifest interrupted at any moment still reads back: a torn last
// line is skipped with a warning). Later lines supersede earlier ones for the same input; a batch
// compacts its manifest to one line per item when it ends.
//
//   {"input":"/data/16_15.bvh","stem":"16_15","item":"16_15","status":"ok","message":"",
//    "wall_seconds":1.2,"graph_seconds":1.1,"log":"logs/16_15.log",
//    "outputs":[{"path":"16_15/16_15.bvh","sha256":"...","bytes":81234}],
//    "reads":[{"path":"/data/16_15.bvh","sha256":"...","bytes":306099}],
//    "figures":{"solve.iterations":12},"input_sha256":"...","graph_sha256":"...",
//    "settings_sha256":"...","finished_at":"2026-11-22T07:00:00Z","host":"node1","shard":"0/4"}
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "kg/graph/node.hpp"

namespace kg::graph {

// A file an item wrote or read.
struct ManifestFile {
  std::string path;  // relative to the batch folder when inside it, else absolute
  std::string sha256;
  std::uintmax_t bytes = 0;
};

struct ManifestRecord {
  std::string input;         // absolute path: the item's key
  std::string stem;          // the input's name without extension (the graph's ${stem})
  std::string item;          // its folder and log name below the batch folder, e.g. "bvh_daz/07_05"
  std::string status;        // "ok" or "failed"
  std::string message;       // why it failed; empty when ok
  double wall_seconds = 0;   // the item's whole time: graph loading, run, hashing outputs
  double graph_seconds = 0;  // the graph's own run
  std::string log;           // relative to the batch folder
  std::vector<ManifestFile> outputs;
  std::vector<ManifestFile> reads;  // every file the graph read: the input, a skeleton, targets, ...
  std::vector<std::pair<std::string, Figure>> figures;  // "node.key", in the order reported
  std::string input_sha256, graph_sha256, settings_sha256;
  std::string finished_at;  // UTC, ISO 8601 to the second
  std::string host;
  std::string shard;  // "I/N", or empty for an unsharded batch

  bool ok() const { return status == "ok"; }
};

// The record as one line of JSON, without the newline.
std::string manifest_line(const ManifestRecord& record);

// One line back into a record. Throws std::runtime_error saying what is wrong with it.
ManifestRecord parse_manifest_line(const std::string& line);

// The records of a manifest file in file order. Lines that do not read as a record (a torn last
// line of an interrupted run, a hand edit) are skipped, each adding "file:line: why" to
// `problems`. A missing file has no records.
std::vector<ManifestRecord> read_manifest(const std::filesystem::path& file,
                                          std::vector<std::string>& problems);

// The latest record per input (by finished_at, then by order given), in order of first appearance.
std::vector<ManifestRecord> latest_records(const std::vector<ManifestRecord>& records);

// The hash identifying a batch's settings: every NAME=VALUE, sorted by name.
std::string settings_sha256(const std::vector<std::pair<std::string, std::string>>& settings);

// What a batch written as Slurm jobs was (DIR/batch.json), so that its array tasks refuse to run
// another graph or other settings and merge can tell stale records from current ones.
struct BatchIdentity {
  std::string graph;  // absolute path
  std::string graph_sha256, settings_sha256;
};
void write_batch_identity(const std::filesystem::path& file, const BatchIdentity& identity);  // atomically
// Throws std::runtime_error naming the file when it cannot be read.
BatchIdentity read_batch_identity(const std::filesystem::path& file);

// The current time as "YYYY-MM-DDTHH:MM:SSZ".
std::string utc_timestamp();

}  // namespace kg::graph
