// `kinegraph batch`: one saved graph over many input files, each item in its own process forked
// from this one (plugins are loaded once, a crash stays within its item, and every item starts
// from the same state, so its outputs do not depend on which items ran before it or where);
// `kinegraph merge`: the manifests of a batch's shards into one. Layout of DIR:
//
//   DIR/ITEM/...                 what the graph writes under ${out}; ITEM is the input's stem, below
//                                the folders that lead to it from the inputs' common folder
//   DIR/logs/ITEM.log            everything the item printed
//   DIR/manifest.jsonl           manifest.hpp; DIR/manifest.shard-I-of-N.jsonl for --shard I/N
//   DIR/.manifest*.lock          held by the one batch writing that manifest
//   DIR/inputs.txt, DIR/slurm/   with --slurm: the frozen input list and the jobs' own logs
//   DIR/batch.json               with --slurm: the graph's and settings' hashes the jobs run with
#pragma once

#include "host.hpp"
#include "options.hpp"

namespace kg::app {

// Returns the exit code (options.hpp); throws Failure for a usage, graph or plugin problem found
// before any item runs.
int batch(Host& host, const Options& o, const char* argv0);

int merge(const Options& o);

}  // namespace kg::app
