// io.import_bvh and io.export_bvh: thin adapters over import_bvh and write_bvh (bvh.hpp); and
// io.export_motion, which writes through the kg.MotionFormat claiming its path's extension
// (motion_format.hpp).
#include <memory>
#include <string>

#include "kg/base/atomic_file.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/io/nodes.hpp"

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

// Both exporters: `format`'s writer over params `path`, `units`, `precision` and `exact`.
class ExportNode final : public graph::Node {
 public:
  ExportNode(const graph::Params& p, std::shared_ptr<const io::MotionFormat> format)
      : format_(std::move(format)), path_(p.get<std::string>("path")) {
    options_.units = p.get<std::string>("units");
    options_.precision = static_cast<int>(p.get<std::int64_t>("precision"));
    options_.exact = p.get<bool>("exact");
    options_.validate();  // a bad setting fails when the graph loads
  }

  void run(graph::RunContext& ctx) const override {
    const motion::Motion& m = ctx.input<motion::Motion>("motion");
    kg::write_file_atomically(path_, [&](std::ostream& os) { format_->write(os, m, options_); });
    ctx.report("path", path_);
    ctx.report("frames", static_cast<std::int64_t>(m.frame_count()));
    ctx.report("units",
               options_.units == "source" ? io::unit_name(m.skeleton->source_unit_metres) : options_.units);
  }

 private:
  std::shared_ptr<const io::MotionFormat> format_;
  std::string path_;
  io::MotionWriteOptions options_;
};

graph::NodeSpec import_spec() {
  graph::NodeSpec spec{
      .type = "io.import_bvh",
      .version = 3,  // 2: trim (calibration frames dropped by default); 3: fps auto
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

graph::NodeSpec export_spec(std::string type, std::string doc, std::string path_doc) {
  using graph::ParamType;
  return {
      .type = std::move(type),
      .version = 1,
      .doc = std::move(doc),
      .inputs = {{"motion", "kg.Motion", true, "the clip to write"}},
      .params =
          {{.name = "path",
            .type = ParamType::OutputPath,
            .default_value = std::string{},
            .doc = std::move(path_doc),
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
            .max = 12},
           {.name = "exact",
            .type = ParamType::Bool,
            .default_value = false,
            .doc = "false: three rotation channels per joint (and three position channels where it has "
                   "any), as every tool reads; true: the skeleton's own channels (an ASF clavicle's two)"}},
      .side_effects = true,
  };
}

graph::NodeType export_bvh_type() {
  return {export_spec(
              "io.export_bvh",
              "Writes a clip as BVH (file axes, degrees, the skeleton's channel orders), atomically. Reading "
              "it back gives the same values to the printed precision.",
              "the .bvh file to write"),
          [](const graph::Params& p) { return std::make_unique<ExportNode>(p, io::bvh_format()); }};
}

// The writer is the one format of the registry claiming the path's extension, found when the
// node is made, so that an unclaimed extension (x.fbx) fails at load rather than getting BVH.
graph::NodeType export_motion_type() {
  graph::NodeType type{
      export_spec("io.export_motion",
                  "Writes a clip in the format its path's extension names, in any case, atomically: .bvh "
                  "(kg.MotionFormat extensions; plugins add more). An extension no writer claims fails the "
                  "graph at load, naming the writers. BVH as io.export_bvh writes it.",
                  "the file to write; its extension picks the format (.bvh)"),
      {}};
  type.create_with_registry = [](const graph::Params& p, const graph::Registry& registry) {
    return std::make_unique<ExportNode>(
        p, io::motion_writer_for(p.get<std::string>("path"), io::motion_formats_in(registry)));
  };
  return type;
}

}  // namespace

std::vector<graph::NodeType> bvh_node_types() {
  return {
      {import_spec(), [](const graph::Params& p) { return std::make_unique<ImportBvhNode>(p); }},
      export_bvh_type(),
      export_motion_type(),
  };
}

}  // namespace kg
