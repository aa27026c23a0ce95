// io.import_asf_amc and io.import_motion: thin adapters over kg/io/asf_amc.hpp and, for
// io.import_motion, the kg.MotionFormat claiming the path's extension (motion_format.hpp).
#include <memory>
#include <string>
#include <vector>

#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/nodes.hpp"

namespace kg {

namespace {

// Both node types: a reader over params `path`, `skeleton` and the import options.
class ImportNode final : public graph::Node {
 public:
  ImportNode(const graph::Params& p, io::MotionReader import)
      : import_(import),
        path_(p.get<std::string>("path")),
        skeleton_(p.get<std::string>("skeleton")),
        options_(io::import_options_from(p)) {}

  void run(graph::RunContext& ctx) const override {
    io::ImportedMotion in = import_(path_, skeleton_, options_);
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

 private:
  io::MotionReader import_;
  std::string path_, skeleton_;
  io::ImportOptions options_;
};

// An ImportNode type: `files` (its path and skeleton params), then the import options.
graph::NodeType import_type(std::string type, std::string doc, std::vector<graph::ParamSpec> files,
                            io::MotionReader import) {
  for (graph::ParamSpec& p : io::import_option_params("auto")) {
    if (p.name == "fps") {
      p.doc =
          "frames per second; 0 keeps a BVH's Frame Time and, for AMC files, which carry no rate, means " +
          std::to_string(static_cast<int>(io::kAmcDefaultFps)) + " (CMU's capture rate)";
    }
    files.push_back(std::move(p));
  }
  graph::NodeSpec spec{
      .type = std::move(type),
      .version = 3,  // 2: trim (calibration frames dropped by default); 3: fps auto
      .doc = std::move(doc),
      .outputs = {{"motion", "kg.Motion", true, "the clip: metres, radians, +Y up (skeleton.file_to_world)"},
                  {"skeleton", "kg.Skeleton", true, "its skeleton (the same object as motion.skeleton)"}},
      .params = std::move(files),
  };
  return {std::move(spec),
          [import](const graph::Params& p) { return std::make_unique<ImportNode>(p, import); }};
}

// io.import_motion's reader: the one format of the registry claiming its path's extension, found
// when the node is made, so that an unclaimed extension fails at load.
graph::NodeType dispatching_by_extension(graph::NodeType type) {
  type.create = {};
  type.create_with_registry = [](const graph::Params& p, const graph::Registry& registry) {
    std::shared_ptr<const io::MotionFormat> format =
        io::motion_reader_for(p.get<std::string>("path"), io::motion_formats_in(registry));
    return std::make_unique<ImportNode>(p, format->read);
  };
  return type;
}

io::ImportedMotion asf_amc_by_path(const std::string& path, const std::string& skeleton,
                                   const io::ImportOptions& options) {
  return io::import_asf_amc(skeleton, path, options);
}

}  // namespace

std::vector<graph::NodeType> asf_amc_node_types() {
  using graph::ParamType;
  return {
      import_type(
          "io.import_asf_amc",
          "Reads an Acclaim skeleton (.asf) and motion (.amc), as in the CMU database: :units (length, "
          "angle), root order and axis, per-bone axis and dof order; limits become joint limits. Lengths "
          "go to metres by the ASF's :units (units auto) or the units param. Strict: a malformed file "
          "fails with file:line.",
          {{.name = "skeleton",
            .type = ParamType::InputPath,
            .default_value = std::string{},
            .doc = "the .asf skeleton file",
            .required = true},
           {.name = "path",
            .type = ParamType::InputPath,
            .default_value = std::string{},
            .doc = "the .amc motion file",
            .required = true}},
          &asf_amc_by_path),
      dispatching_by_extension(import_type(
          "io.import_motion",
          "Reads a motion file in the format its extension names, in any case: .bvh or .amc (kg.MotionFormat "
          "extensions; plugins add more). An extension no reader claims fails the graph at load, naming the "
          "readers. An .amc needs its .asf skeleton: given by `skeleton`, or else the file named by the "
          "AMC's subject prefix in the same folder (16_15.amc -> 16.asf), said in the log.",
          {{.name = "path",
            .type = ParamType::InputPath,
            .default_value = std::string{},
            .doc = "the motion file: .bvh or .amc",
            .required = true},
           {.name = "skeleton",
            .type = ParamType::InputPath,
            .default_value = std::string{},
            .doc = "the .asf skeleton of an .amc (\"\": guessed from the name); must be \"\" for a .bvh"}},
          io::MotionReader{})),
  };
}

}  // namespace kg
