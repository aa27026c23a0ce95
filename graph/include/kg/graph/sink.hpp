// What every sink node (a node that writes a file: DESIGN.md 13) does with its `path` param: an
// empty path (a graph variable left empty) writes nothing and says so; any other is written
// atomically (a temporary file renamed). Either way the node reports the figure `written`.
//
//   .params = {sink_path_param("the JSON file; \"\" writes none")},
//   ...
//   write_sink_file(ctx, path_, [&](std::ostream& os) { report.write(os); });
#pragma once

#include <functional>
#include <ostream>
#include <string>

#include "kg/graph/node.hpp"

namespace kg::graph {

// The `path` param of a sink: an output path, "" by default (writes none).
ParamSpec sink_path_param(const std::string& doc);

// Writes what `write` prints to `path` atomically and reports written: true; with an empty path
// logs "no path: nothing written" and reports written: false.
void write_sink_file(RunContext& ctx, const std::string& path,
                     const std::function<void(std::ostream&)>& write);

}  // namespace kg::graph
