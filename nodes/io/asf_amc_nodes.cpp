// io.import_asf_amc and io.import_motion: thin adapters over kg/io/asf_amc.hpp (DESIGN.md 7).
#include <memory>

#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"

namespace kg {

namespace {

using graph::Node;
using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;

const std::vector<graph::PortSpec> kOutputs{
    {"motion", "kg.Motion", true, "the clip: metres, radians, +Y up (skeleton.file_to_world)"},
    {"skeleton", "kg.Skeleton", true, "its skeleton (the same object as motion.skeleton)"}};

void publish(RunContext& ctx, io::ImportedMotion in) {
  for (const std::string& note : in.notes) ctx.log(note);
  const motion::Motion& m = in.motion;
  ctx.report("frames", static_cast<std::int64_t>(m.frame_count()));
  ctx.report("fps", m.fps);
  ctx.report("duration_s", m.duration());
  ctx.report("joints", static_cast<std::int64_t>(m.skeleton->joint_count()));
  ctx.report("channels", static_cast<std::int64_t>(m.skeleton->channel_count()));
  ctx.report("units", io::unit_name(m.skeleton->source_unit_metres));
  ctx.report("up", io::up_axis_name(m.skeleton->file_to_world));
  ctx.report("height_m", m.skeleton->rest_height());
  ctx.set_output("skeleton", graph::Value::share(m.skeleton));
  ctx.output("motion", std::move(in.motion));
}

class ImportAsfAmcNode final : public Node {
 public:
  explicit ImportAsfAmcNode(const Params& p)
      : asf_(p.get<std::string>("skeleton")),
        amc_(p.get<std::string>("path")),
        options_(io::import_options_from(p)) {}

  void run(RunContext& ctx) const override { publish(ctx, io::import_asf_amc(asf_, amc_, options_)); }

 private:
  std::string asf_, amc_;
  io::ImportOptions options_;
};

class ImportMotionNode final : public Node {
 public:
  explicit ImportMotionNode(const Params& p)
      : path_(p.get<std::string>("path")),
        skeleton_(p.get<std::string>("skeleton")),
        options_(io::import_options_from(p)) {}

  void run(RunContext& ctx) const override { publish(ctx, io::import_motion(path_, skeleton_, options_)); }

 private:
  std::string path_, skeleton_;
  io::ImportOptions options_;
};

std::vector<ParamSpec> with_import_options(std::vector<ParamSpec> params) {
  for (ParamSpec& p : io::import_option_params("auto")) {
    if (p.name == "fps") {
      p.doc =
          "frames per second; 0 keeps a BVH's Frame Time and, for AMC files, which carry no rate, means " +
          std::to_string(static_cast<int>(io::kAmcDefaultFps)) + " (CMU's capture rate)";
    }
    params.push_back(std::move(p));
  }
  return params;
}

NodeType import_asf_amc_type() {
  NodeSpec spec;
  spec.type = "io.import_asf_amc";
  spec.version = 1;
  spec.doc =
      "Reads an Acclaim skeleton (.asf) and motion (.amc), as in the CMU database: :units (length, angle), "
      "root order and axis, per-bone axis and dof order; limits become joint limits. Lengths go to metres "
      "by the ASF's :units (units auto) or the units param. Strict: a malformed file fails with file:line.";
  spec.outputs = kOutputs;
  ParamSpec skeleton{"skeleton", ParamType::InputPath, std::string{}, "the .asf skeleton file", true};
  ParamSpec path{"path", ParamType::InputPath, std::string{}, "the .amc motion file", true};
  spec.params = with_import_options({skeleton, path});
  return {spec, [](const Params& p) { return std::make_unique<ImportAsfAmcNode>(p); }};
}

NodeType import_motion_type() {
  NodeSpec spec;
  spec.type = "io.import_motion";
  spec.version = 1;
  spec.doc =
      "Reads a .bvh or an .amc file, chosen by the extension. An .amc needs its .asf skeleton: given by "
      "`skeleton`, or else the file named by the AMC's subject prefix in the same folder (16_15.amc -> "
      "16.asf), "
      "said in the log.";
  spec.outputs = kOutputs;
  ParamSpec path{"path", ParamType::InputPath, std::string{}, "the motion file: .bvh or .amc", true};
  ParamSpec skeleton{"skeleton", ParamType::InputPath, std::string{},
                     "the .asf skeleton of an .amc (\"\": guessed from the name); must be \"\" for a .bvh"};
  spec.params = with_import_options({path, skeleton});
  return {spec, [](const Params& p) { return std::make_unique<ImportMotionNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> asf_amc_node_types() {
  return {import_asf_amc_type(), import_motion_type()};
}

}  // namespace kg
