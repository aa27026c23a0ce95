// motion.inspect: the motion doctor as a node (kg/motion/inspect.hpp), for batch manifests and
// `kinegraph inspect`. Here in io rather than motion because it names the clip's length unit as
// the importers do (io::unit_name).
#include <memory>
#include <string>

#include "kg/base/json.hpp"
#include "kg/base/report.hpp"
#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/node.hpp"
#include "kg/io/import_options.hpp"
#include "kg/motion/inspect.hpp"
#include "kg/motion/nodes.hpp"

namespace kg {
namespace {

class InspectNode final : public graph::Node {
 public:
  explicit InspectNode(const graph::Params& p) {
    options_.plants.points = motion::split_names(p.get<std::string>("points"));
    options_.plants.floor = motion::parse_floor(p.get<std::string>("floor"));
    options_.validate();
  }

  void run(graph::RunContext& ctx) const override {
    const motion::Motion& clip = ctx.input<motion::Motion>("motion");
    const motion::MotionInspection i = motion::inspect_motion(clip, options_);
    for (const std::string& line : i.summary) ctx.log(line);
    const std::string units = io::unit_name(i.unit_metres);
    ctx.report("up", i.up);
    ctx.report("units", units);
    ctx.report("header_fps", i.header_fps);
    ctx.report("source_fps", i.source_fps);
    ctx.report("calibration_frames", static_cast<std::int64_t>(i.calibration_frames.size()));
    std::int64_t plants = 0;
    double skate = 0;
    for (const motion::PointPlants& p : i.plants) {
      ctx.report("plants." + p.point, static_cast<std::int64_t>(p.spans.size()));
      plants += static_cast<std::int64_t>(p.spans.size());
      skate = std::max(skate, p.worst_skate);
    }
    ctx.report("plants", plants);
    ctx.report("skate_max_m", skate);
    ctx.report("flights", static_cast<std::int64_t>(i.flights.size()));
    ctx.report("penetration_m", i.penetration);
    ctx.report("pops", static_cast<std::int64_t>(i.pops.size()));
    ctx.report("fixes", text::join(i.fixes, " "));
    Report report;
    {
      JsonWriter w(report);
      motion::write_inspection_json(w, i, units);
    }
    ctx.output("report", std::move(report));
  }

 private:
  motion::InspectOptions options_;
};

graph::NodeType inspect_type() {
  graph::NodeSpec spec{
      .type = "motion.inspect",
      .version = 1,
      .doc =
          "The motion doctor: the joint tree (names, channels, rest lengths), frames and rate, the up axis "
          "and unit the clip was read with, calibration frames (a T-pose or A-pose before the motion), "
          "footplants per foot point with their skate, flights with the gravity each implies (and the "
          "frame rate that gravity implies, when the header's is off by a whole factor), floor "
          "penetration, pops (frames where a joint's velocity jumps), and the --set values that fix what "
          "it found. Feed it the clip with every frame (io.import_motion with trim: none). Its report is "
          "JSON (io.write_report); its figures go into batch manifests.",
      .inputs = {{"motion", "kg.Motion", true, "the clip, every frame kept"}},
      .outputs = {{"report", "kg.Report", true,
                   "up, units, header_fps, source_fps, calibration_frames, plants, flights (each with its "
                   "gravity), penetration, pops, fixes, summary"}},
      .params = {{.name = "points",
                  .type = graph::ParamType::String,
                  .default_value = std::string(),
                  .doc = "foot points as for retarget.footplants ('Joint', 'Joint/end', 'Joint[x y z]'); "
                         "empty: per foot the ankle and the toe tip, by common names"},
                 {.name = "floor",
                  .type = graph::ParamType::String,
                  .default_value = std::string("auto"),
                  .doc = "floor height in metres, or auto (a low percentile of the lowest foot point)"}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<InspectNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> inspect_node_types() {
  return {inspect_type()};
}

}  // namespace kg
