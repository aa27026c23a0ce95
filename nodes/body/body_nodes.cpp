// retime.body_model: a thin adapter over body_build.hpp.
#include <cmath>
#include <limits>
#include <memory>

#include "kg/base/text.hpp"
#include "kg/body/body_build.hpp"
#include "kg/body/nodes.hpp"
#include "kg/body/robot_body.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/motion/motion.hpp"

namespace kg {
namespace {

using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamType;
using graph::RunContext;

std::string describe(const std::string& key, const body::BodySpec& s) {
  if (key == "table") return body::to_string(s.table);
  if (key == "mass") return text::significant(s.mass, 4) + " kg";
  if (key == "friction") return text::significant(s.friction, 4);
  const Eigen::Vector3d& g = s.gravity;
  return "[" + text::significant(g.x(), 4) + ", " + text::significant(g.y(), 4) + ", " +
         text::significant(g.z(), 4) + "] m/s²";
}

class BodyModelNode final : public graph::Node {
 public:
  explicit BodyModelNode(const Params& p) : path_(p.get<std::string>("file")) {
    const auto table = body::body_table_from_string(p.get<std::string>("table"));
    if (!table) throw std::invalid_argument("table '" + p.get<std::string>("table") + "': unknown");
    spec_.table = *table;
    spec_.mass = p.get<double>("mass");
    spec_.friction = p.get<double>("friction");
    spec_.gravity = Eigen::Vector3d(0, -p.get<double>("gravity"), 0);
    // Without a file the params are the whole spec: refuse a bad one when the graph loads.
    if (path_.empty() && spec_.table != body::BodyTable::Cylinders && !(spec_.mass > 0))
      throw std::invalid_argument("mass " + text::significant(spec_.mass, 4) + " kg with table " +
                                  body::to_string(spec_.table) +
                                  ": expected > 0 (0 means 'from the volumes' only with cylinders)");
  }

  void run(RunContext& ctx) const override {
    const auto& m = ctx.input<motion::Motion>("motion");
    if (text::lower_extension(path_) == ".urdf") return run_robot(ctx, m);
    body::BodySpec spec = spec_;
    if (!path_.empty()) {
      const body::LoadedBodySpec file = body::load_body_yaml(path_, spec_);
      for (const std::string& key : file.given)
        if (key == "table" || key == "mass" || key == "friction" || key == "gravity")
          ctx.log("body file " + path_ + " sets " + key + " = " + describe(key, file.spec) + " (param " +
                  key + " = " + describe(key, spec_) + " not used)");
      spec = file.spec;
    }
    // The anatomical directions: frame 0 (the T-pose the Daz and iClone exports prepend, a
    // standing frame for most clips), the rest pose for a clip without frames.
    const Eigen::RowVectorXd ref =
        m.frame_count() > 0 ? Eigen::RowVectorXd(m.values.row(0)) : body::rest_pose_values(*m.skeleton);
    body::BuiltBody built = body::build_body_model(m.skeleton, spec, &ref);
    for (const std::string& note : built.notes) ctx.log(note);

    const body::BodyModel& body = built.body;
    std::string summary = "total " + text::significant(body.total_mass(), 4) + " kg:";
    for (int c = 0; c < body::kSegmentClassCount; ++c) {
      const auto sc = static_cast<body::SegmentClass>(c);
      const double kg = built.class_mass[static_cast<std::size_t>(c)];
      summary +=
          std::string(c ? "," : "") + " " + body::to_string(sc) + " " + text::significant(kg, 4) + " kg";
      ctx.report(std::string("mass_") + body::to_string(sc), kg);
    }
    ctx.log(summary);
    ctx.report("table", std::string(body::to_string(spec.table)));
    ctx.report("total_mass", body.total_mass());
    std::int64_t massive = 0, limited = 0, unactuated = 0;
    for (const body::SegmentInertia& s : body.segments) massive += s.mass > 0;
    for (Eigen::Index c = 0; c < body.torque_max.size(); ++c) {
      unactuated += body.torque_min[c] == 0 && body.torque_max[c] == 0;
      limited += std::isfinite(body.torque_max[c]) && body.torque_max[c] > 0;
    }
    ctx.report("segments_with_mass", massive);
    ctx.report("channels_unactuated", unactuated);
    ctx.report("channels_limited", limited);
    ctx.report("friction", body.friction);
    ctx.report("gravity", body.gravity.norm());
    if (m.frame_count() > 0) {
      // A plausibility figure: the CoM's height in frame 0 as a fraction of the figure's height
      // there (about 0.55 standing).
      const Eigen::Vector3d com = body::body_com(body, ref);
      std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
      motion::forward_kinematics(*m.skeleton, ref, world);
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int j = 0; j < m.skeleton->joint_count(); ++j) {
        lo = std::min(lo, world[static_cast<std::size_t>(j)].translation().y());
        hi = std::max(hi, world[static_cast<std::size_t>(j)].translation().y());
        for (const Eigen::Vector3d& e : m.skeleton->joint(j).end_sites) {
          const double y = (world[static_cast<std::size_t>(j)] * e).y();
          lo = std::min(lo, y);
          hi = std::max(hi, y);
        }
      }
      if (hi > lo) ctx.report("com_height_fraction_frame0", (com.y() - lo) / (hi - lo));
    }
    ctx.output("body", std::move(built.body));
  }

 private:
  // The robot's own links and effort limits (robot_body.hpp); table and mass do not apply.
  void run_robot(RunContext& ctx, const motion::Motion& m) const {
    const io::Robot robot = io::read_urdf(path_);
    body::RobotBody built = body::robot_body_model(robot, m.skeleton, spec_.friction, -spec_.gravity.y());
    for (const std::string& note : built.notes) ctx.log(note);
    const body::BodyModel& body = built.body;
    std::int64_t massive = 0;
    for (const body::SegmentInertia& s : body.segments) massive += s.mass > 0;
    ctx.report("table", std::string("urdf"));
    ctx.report("total_mass", body.total_mass());
    ctx.report("segments_with_mass", massive);
    ctx.report("channels_unactuated", static_cast<std::int64_t>(m.skeleton->joint(0).channels.size()));
    ctx.report("channels_limited", static_cast<std::int64_t>(built.channels_limited));
    ctx.report("friction", body.friction);
    ctx.report("gravity", body.gravity.norm());
    ctx.output("body", std::move(built.body));
  }

  body::BodySpec spec_;
  std::string path_;
};

NodeType body_model_type() {
  NodeSpec spec{
      .type = "retime.body_model",
      .version = 2,
      .doc =
          "The physical character of a clip's skeleton (McCann et al. 2006 §4): every joint's segment mass, "
          "centre of mass and inertia from a published table (Dempster, Zatsiorsky-Seluyanov, de Leva) or "
          "from "
          "water cylinders, joints mapped to table segments by name patterns, plus torque limits, friction "
          "and "
          "gravity. A body `file` (YAML, version 1) maps joints, overrides segments (a thigh ten times "
          "heavier) "
          "and sets torque limits; its table, mass, friction and gravity replace the params (said in the "
          "log).",
      .inputs = {{"motion", "kg.Motion", true,
                  "the clip (its skeleton is the body; frame 0 orients the inertias)"}},
      .outputs = {{"body", "kg.BodyModel", true,
                   "masses, CoMs, inertias per joint, torque bounds per channel"}},
      .params = {
          {.name = "table",
           .type = ParamType::Enum,
           .default_value = std::string("de_leva_male"),
           .doc = "segment parameters: dempster, zatsiorsky_male, zatsiorsky_female, de_leva_male, "
                  "de_leva_female, or cylinders (solid cylinders of water along the bones)",
           .choices = body::body_table_names()},
          {.name = "mass",
           .type = ParamType::Float,
           .default_value = 70.0,
           .doc = "body mass, kg (> 0; with cylinders 0 means the volumes' own mass)",
           .min = 0.0,
           .max = 1000.0},
          {.name = "file",
           .type = ParamType::InputPath,
           .default_value = std::string(),
           .doc = "optional body YAML: classes, segment overrides, torque_limits (see body_build.hpp); "
                  "its table/mass/friction/gravity replace the params. Or a robot's .urdf: its links' "
                  "inertials and its joints' effort limits (robot_body.hpp; table, mass and torque_limits "
                  "do not apply), for a motion on that robot"},
          {.name = "friction",
           .type = ParamType::Float,
           .default_value = 0.5,
           .doc = "Coulomb friction coefficient of every contact",
           .min = 0.0,
           .max = 100.0},
          {.name = "gravity",
           .type = ParamType::Float,
           .default_value = 9.81,
           .doc = "gravity, m/s², straight down (world -Y); a body file may give a vector",
           .min = 0.0,
           .max = 1000.0},
          {.name = "torque_limits",
           .type = ParamType::Enum,
           .default_value = std::string("given"),
           .doc = "given: the body file's torque_limits, unlimited elsewhere (the floating base always "
                  "unactuated); estimation from the source's own torques with a margin is to come",
           .choices = {"given"}}}};
  return {spec, [](const Params& p) { return std::make_unique<BodyModelNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> retime_body_node_types() {
  return {body_model_type()};
}

}  // namespace kg
