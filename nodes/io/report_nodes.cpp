// io.write_report: the sink writing a kg.Report (a solver's report, retarget.metrics' figures) as
// a JSON file; the solvers themselves write no files (DESIGN.md 13).
#include <memory>
#include <string>

#include "kg/base/report.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/node.hpp"
#include "kg/graph/sink.hpp"

namespace kg {
namespace {

class WriteReportNode final : public graph::Node {
 public:
  explicit WriteReportNode(const graph::Params& p) : path_(p.get<std::string>("path")) {}

  void run(graph::RunContext& ctx) const override {
    const Report& report = ctx.input<Report>("report");
    // The document's text and a blank line, as the project's reports have always ended.
    graph::write_sink_file(ctx, path_, [&](std::ostream& os) {
      report.write(os);
      os << '\n';
    });
  }

 private:
  std::string path_;
};

graph::NodeType write_report_type() {
  graph::NodeSpec spec{
      .type = "io.write_report",
      .version = 1,
      .doc =
          "Writes a report (retime.retime's, retarget.metrics') as a JSON file, atomically: pretty-printed "
          "with "
          "two spaces, numbers in their shortest exact form, then a blank line. A report its node set before "
          "failing (retime.retime with strict) is written all the same, saying why.",
      .inputs = {{"report", "kg.Report", true, "the document"}},
      .params = {graph::sink_path_param("the .json file; \"\" writes none (logged)")},
      .side_effects = true};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<WriteReportNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> report_node_types() {
  return {write_report_type()};
}

}  // namespace kg
