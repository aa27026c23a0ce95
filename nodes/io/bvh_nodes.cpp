// io.import_bvh and io.export_bvh: thin adapters over import_bvh and write_bvh (bvh.hpp).
#include <memory>
#include <string>

#include "kg/builtin_nodes.hpp"
#include "kg/io/nodes.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"

namespace kg {
namespace {

class ImportBvhNode final : public graph::Node {
 public:
  explicit ImportBvhNode(const graph::Params& p)
      : path_(p.get<std::string>("path")), options_(io::import_options_from(p)) {}

  void run(graph::RunContext& ctx) const override {
    io::ImportedMotion in = io::import_bvh(path_, options_);
    for (const std::string& note : in.notes) ctx.log(note);
    const motion::Motion& m = in.motion;
    const motion::Skeleton& s = *m.skeleton;
    ctx.report("frames", static_cast<std::int64_t>(m.frame_count()));
    ctx.report("joints", static_cast<std::int64_t>(s.joint_count()));
    ctx.report("channels", static_cast<std::int64_t>(s.channel_count()));
    ctx.report("fps", m.fps);
    ctx.report("file_fps", 1.0 / in.file_frame_time);
    ctx.report("seconds", m.duration());
    ctx.report("units", io::unit_name(s.source_unit_metres));
    ctx.report("up", io::up_axis_name(s.file_to_world));
    if (!in.notes.empty()) {
      std::string all;
      for (const std::string& note : in.notes) all += (all.empty() ? "" : "\n") + note;
      ctx.report("notes", all);
    }
    ctx.set_output("skeleton", graph::Value::share(m.skeleton));
    ctx.output("motion", std::move(in.motion));
  }

 private:
  std::string path_;
  io::ImportOptions options_;
};

class ExportBvhNode final : public graph::Node {
 public:
  explicit ExportBvhNode(const graph::Params& p) : path_(p.get<std::string>("path")) {
    options_.units = p.get<std::string>("units");
    options_.precision = static_cast<int>(p.get<std::int64_t>("precision"));
  }

  void run(graph::RunContext& ctx) const override {
    const motion::Motion& m = ctx.input<motion::Motion>("motion");
    kg::write_file_atomically(path_, [&](std::ostream& os) { io::write_bvh(os, m, options_); });
    ctx.report("path", path_);
    ctx.report("frames", static_cast<std::int64_t>(m.frame_count()));
    ctx.report("units",
               options_.units == "source" ? io::unit_name(m.skeleton->source_unit_metres) : options_.units);
  }

 private:
  std::string path_;
  io::BvhWriteOptions options_;
};

graph::NodeSpec import_spec() {
  graph::NodeSpec spec{
      .type = "io.import_bvh",
      .version = 1,
      .doc =
          "Reads a BVH file (strictly: a malformed file fails with file:line) and brings it to metres, "
          "radians and +Y up. Position channels replace the OFFSET components they name. units/up auto "
          "guess from the figure and log what they chose.",
      .outputs = {{"motion", "kg.Motion", true, "the clip: metres, radians, file channel orders"},
                  {"skeleton", "kg.Skeleton", true, "its skeleton (the same one the motion holds)"}},
      .params = {{.name = "path",
                  .type = graph::ParamType::InputPath,
                  .default_value = std::string{},
                  .doc = "the .bvh file to read",
                  .required = true}},
  };
  for (graph::ParamSpec& p : io::import_option_params()) spec.params.push_back(std::move(p));
  return spec;
}

graph::NodeSpec export_spec() {
  using graph::ParamType;
  return {
      .type = "io.export_bvh",
      .version = 1,
      .doc =
          "Writes a clip as BVH (file axes, degrees, the skeleton's channel orders), atomically. Reading it "
          "back gives the same values to the printed precision.",
      .inputs = {{"motion", "kg.Motion", true, "the clip to write"}},
      .params = {{.name = "path",
                  .type = ParamType::OutputPath,
                  .default_value = std::string{},
                  .doc = "the .bvh file to write",
                  .required = true},
                 {.name = "units",
                  .type = ParamType::Enum,
                  .default_value = std::string("source"),
                  .doc = "length unit written: source (the unit the clip was read in), m, cm, mm, inch",
                  .choices = {"source", "m", "cm", "mm", "inch"}},
                 {.name = "precision",
                  .type = ParamType::Int,
                  .default_value = std::int64_t{6},
                  .doc = "digits after the decimal point (trailing zeros dropped)",
                  .min = 1,
                  .max = 12}},
  };
}

}  // namespace

std::vector<graph::NodeType> bvh_node_types() {
  return {
      {import_spec(), [](const graph::Params& p) { return std::make_unique<ImportBvhNode>(p); }},
      {export_spec(), [](const graph::Params& p) { return std::make_unique<ExportBvhNode>(p); }},
  };
}

}  // namespace kg
