#include "kg/graph/sink.hpp"

#include "kg/base/atomic_file.hpp"

namespace kg::graph {

ParamSpec sink_path_param(const std::string& doc) {
  return {.name = "path", .type = ParamType::OutputPath, .default_value = std::string(), .doc = doc};
}

void write_sink_file(RunContext& ctx, const std::string& path,
                     const std::function<void(std::ostream&)>& write) {
  if (path.empty()) {
    ctx.log("no path: nothing written");
    ctx.report("written", false);
    return;
  }
  kg::write_file_atomically(path, write);
  ctx.report("written", true);
}

}  // namespace kg::graph
