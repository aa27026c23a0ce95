// retarget.footplants, retarget.constraints, retarget.merge_constraints: thin adapters over
// footplants.hpp and constraint_io.hpp (DESIGN.md 7).
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/footplants.hpp"
#include "kg/retarget/holds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/target.hpp"

namespace kg {

namespace {

using graph::Node;
using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;

std::string count_summary(const std::map<std::string, int>& kinds) {
  std::string out;
  for (const auto& [k, n] : kinds) out += (out.empty() ? "" : ", ") + k + " " + std::to_string(n);
  return out;
}

void report_set(RunContext& ctx, const retarget::ConstraintSet& set) {
  std::map<std::string, int> kinds;
  std::int64_t samples = 0;
  for (const retarget::Constraint& c : set.constraints) {
    ++kinds[c.kind];
    samples += static_cast<std::int64_t>(c.samples.size());
  }
  ctx.report("constraints", static_cast<std::int64_t>(set.constraints.size()));
  ctx.report("samples", samples);
  ctx.report("kinds", count_summary(kinds));
}

const graph::PortSpec kConstraintsOut{"constraints", "kg.Constraints", true,
                                      "the constraint set (points on segments at frames; metres, radians)"};

// ---- retarget.footplants ---------------------------------------------------------------------
class FootplantsNode final : public Node {
 public:
  explicit FootplantsNode(const Params& p) {
    detect_.points = motion::split_names(p.get<std::string>("points"));
    detect_.height_threshold = p.get<double>("height_threshold");
    detect_.speed_threshold = p.get<double>("speed_threshold");
    detect_.hysteresis = p.get<double>("hysteresis");
    detect_.min_duration_s = p.get<double>("min_duration_s");
    detect_.trim_distance = p.get<double>("trim_distance");
    detect_.bridge_s = p.get<double>("bridge_s");
    detect_.bridge_distance = p.get<double>("bridge_distance");
    detect_.body_relative = p.get<double>("body_relative");
    detect_.run_froude = p.get<double>("run_froude");
    detect_.rest_window_s = p.get<double>("rest_window_s");
    detect_.floor = motion::parse_floor(p.get<std::string>("floor"));
    detect_.character = static_cast<int>(p.get<std::int64_t>("character"));
    make_.flavour = p.get<std::string>("flavour") == "floor" ? retarget::PlantFlavour::Floor
                                                             : retarget::PlantFlavour::Fixed;
    make_.above_floor = p.get<bool>("above_floor");
    strict_ = p.get<bool>("strict");
    detect_.validate();  // a bad setting fails when the graph loads
    make_.validate();
  }

  void run(RunContext& ctx) const override {
    const motion::Motion& m = ctx.input<motion::Motion>("motion");
    const motion::FootplantDetection d = motion::detect_footplants(m, detect_);
    for (const std::string& note : d.notes) ctx.log(note);
    if (strict_ && !d.warnings.empty())
      throw std::runtime_error(d.warnings.front() +
                               (d.warnings.size() > 1
                                    ? " (and " + std::to_string(d.warnings.size() - 1) + " more point(s))"
                                    : "") +
                               "; strict: no plant on a point that touches the floor");
    for (const std::string& warning : d.warnings) ctx.log("warning: " + warning);
    ctx.report("points_without_plants", static_cast<std::int64_t>(d.warnings.size()));
    for (std::size_t i = 0; i < d.points.size(); ++i)
      ctx.report("plants." + d.points[i].name, static_cast<std::int64_t>(d.count(static_cast<int>(i))));
    ctx.report("plants", static_cast<std::int64_t>(d.plants.size()));
    ctx.report("floor_m", d.floor);
    double skate = 0;
    for (const motion::Footplant& p : d.plants) skate = std::max(skate, p.skate);
    ctx.report("source_skate_max_m", skate);
    retarget::PlantConstraintOptions make = make_;
    if (ctx.has_input("target")) {
      make.height_scale = retarget::plant_height_scale(ctx.input<retarget::Target>("target"), m.fps);
      for (const motion::PlantPoint& p : d.points)
        ctx.report("height_scale." + p.name, make.height_scale(p.point, 0));
    }
    retarget::ConstraintSet set = retarget::footplant_constraints(d, m.frame_count(), make);
    report_set(ctx, set);
    ctx.output("constraints", std::move(set));
  }

 private:
  motion::FootplantOptions detect_;
  retarget::PlantConstraintOptions make_;
  bool strict_ = false;
};

// The params of retarget.footplants: motion::FootplantOptions and retarget::PlantConstraintOptions.
std::vector<ParamSpec> footplants_params() {
  ParamSpec flavour = ParamSpec{.name = "flavour",
                                .type = ParamType::Enum,
                                .default_value = std::string("fixed"),
                                .doc = "fixed: plant positions kept; floor: height plus non-skid only"};
  flavour.choices = {"fixed", "floor"};
  return {
      ParamSpec{.name = "points",
                .type = ParamType::String,
                .default_value = std::string(),
                .doc = "comma-separated points: 'Joint' (its origin), 'Joint/end' (its End Site) or 'Joint[x "
                       "y z]' (metres "
                       "in the joint's frame, e.g. a heel); empty: per foot the ankle and the toe tip, found "
                       "by common names"},
      flavour,
      ParamSpec{.name = "height_threshold",
                .type = ParamType::Float,
                .default_value = 0.03,
                .doc = "m above the point's rest level to enter a plant",
                .min = 1e-6,
                .max = 10.0},
      ParamSpec{.name = "speed_threshold",
                .type = ParamType::Float,
                .default_value = 0.15,
                .doc = "m/s horizontal speed to enter a plant",
                .min = 1e-6,
                .max = 100.0},
      ParamSpec{.name = "hysteresis",
                .type = ParamType::Float,
                .default_value = 1.5,
                .doc = "leave thresholds = enter thresholds x this",
                .min = 1.0,
                .max = 10.0},
      ParamSpec{.name = "min_duration_s",
                .type = ParamType::Float,
                .default_value = 0.08,
                .doc = "shorter plants are dropped, seconds",
                .min = 0.0,
                .max = 10.0},
      ParamSpec{.name = "body_relative",
                .type = ParamType::Float,
                .default_value = motion::FootplantOptions{}.body_relative,
                .doc = "where the body runs, a point slower than this share of its pace may be planted (a "
                       "run's stance foot rolls at up to 1.5 m/s; 0: none)",
                .min = 0.0,
                .max = 0.99},
      ParamSpec{
          .name = "run_froude",
          .type = ParamType::Float,
          .default_value = motion::FootplantOptions{}.run_froude,
          .doc = "the body runs where v^2 / (g h) of its pace passes this (0.5: the walk-run transition)",
          .min = 0.01,
          .max = 100.0},
      ParamSpec{.name = "bridge_s",
                .type = ParamType::Float,
                .default_value = motion::FootplantOptions{}.bridge_s,
                .doc = "a lift shorter than this (seconds) between two plants of a point, back within "
                       "bridge_distance of where it left, is jitter: one plant (0: none)",
                .min = 0.0,
                .max = 1.0},
      ParamSpec{.name = "bridge_distance",
                .type = ParamType::Float,
                .default_value = motion::FootplantOptions{}.bridge_distance,
                .doc = "metres, horizontal: how far from where it left a point may come back for bridge_s",
                .min = 0.0,
                .max = 1.0},
      ParamSpec{
          .name = "trim_distance",
          .type = ParamType::Float,
          .default_value = 0.01,
          .doc = "m: a plant's end frames farther than this from its median position are trimmed (0: none)",
          .min = 0.0,
          .max = 1.0},
      ParamSpec{.name = "rest_window_s",
                .type = ParamType::Float,
                .default_value = 1.0,
                .doc = "s: a point's rest level is its lowest height within this window around each frame "
                       "(0: over the "
                       "whole clip)",
                .min = 0.0,
                .max = 100.0},
      ParamSpec{
          .name = "floor",
          .type = ParamType::String,
          .default_value = std::string("auto"),
          .doc = "floor height in metres, or 'auto' (a low percentile of the lowest foot point's heights)"},
      ParamSpec{.name = "above_floor",
                .type = ParamType::Bool,
                .default_value = false,
                .doc = "also keep every foot point above the floor at every frame"},
      ParamSpec{.name = "strict",
                .type = ParamType::Bool,
                .default_value = false,
                .doc = "true: fail when a point touches the floor (stays within height_threshold of its rest "
                       "level for min_duration_s) and gets no plant; false: a warning with the numbers"},
      ParamSpec{.name = "character",
                .type = ParamType::Int,
                .default_value = std::int64_t{0},
                .doc = "which character of the solve the plants belong to (0 first, 1 second: motion2)",
                .min = 0.0,
                .max = 1.0},
  };
}

NodeType footplants_type() {
  NodeSpec spec;
  spec.type = "retarget.footplants";
  spec.doc =
      "Detects footplants (Gleicher 1998 §3.5): spans where a foot point is near the floor and nearly still "
      "(height and horizontal-speed thresholds with hysteresis, a minimum duration), and emits them as "
      "constraints: fixed (the plant's mean position, all axes) or floor (its height only, plus non-skid "
      "same_place between consecutive frames: the solver may move the plant). With above_floor, every foot "
      "point "
      "stays above the floor (an estimated floor never lifts a point above where the source had it). With a "
      "target connected, heights above the floor are scaled to its size.";
  spec.inputs = {
      {"motion", "kg.Motion", true, "the source clip the plants are read from"},
      {"target", "kg.Target", false,
       "the character the plants are for (of `character`): heights above the floor scale with its feet (a "
       "smaller foot rests lower); horizontal positions stay the source's"}};
  spec.outputs = {kConstraintsOut};
  spec.params = footplants_params();
  return {spec, [](const Params& p) { return std::make_unique<FootplantsNode>(p); }};
}

// ---- retarget.constraints --------------------------------------------------------------------
class ConstraintsNode final : public Node {
 public:
  explicit ConstraintsNode(const Params& p)
      : path_(p.get<std::string>("path")), joint_limits_(p.get<bool>("joint_limits")) {}

  void run(RunContext& ctx) const override {
    const motion::Motion& m = ctx.input<motion::Motion>("motion");
    std::vector<motion::Motion> characters{m};
    if (ctx.has_input("motion2")) characters.push_back(ctx.input<motion::Motion>("motion2"));
    retarget::ConstraintSet set;
    if (ctx.has_input("constraints")) set = ctx.input<retarget::ConstraintSet>("constraints");
    if (!path_.empty()) retarget::merge_constraints(set, retarget::read_constraints_file(path_, characters));
    if (joint_limits_) {
      const retarget::ConstraintSet limits =
          retarget::joint_limit_constraints(*m.skeleton, 0, m.frame_count());
      ctx.report("joint_limits", static_cast<std::int64_t>(limits.constraints.size()));
      if (limits.constraints.empty()) ctx.log("the skeleton has no channel limits");
      retarget::merge_constraints(set, limits);
    }
    report_set(ctx, set);
    ctx.output("constraints", std::move(set));
  }

 private:
  std::string path_;
  bool joint_limits_;
};

NodeType constraints_type() {
  NodeSpec spec;
  spec.type = "retarget.constraints";
  spec.doc =
      "Reads a constraint file (YAML, version 1: constraints naming joints, frame ranges or times, "
      "joint limits by regular expression; see kg/retarget/constraint_io.hpp), adds the skeleton's own "
      "channel limits (ASF limits) if asked, and merges them with the constraints on the input.";
  spec.inputs = {
      {"motion", "kg.Motion", true, "the clip whose skeleton resolves joint names and bounds frames"},
      {"constraints", "kg.Constraints", false, "constraints to merge with (e.g. footplants)"},
      {"motion2", "kg.Motion", false, "the second character's clip, for points with `character: 1`"}};
  spec.outputs = {kConstraintsOut};
  spec.params = {
      ParamSpec{.name = "path",
                .type = ParamType::InputPath,
                .default_value = std::string(),
                .doc = "the constraint YAML file; empty: none"},
      ParamSpec{.name = "joint_limits",
                .type = ParamType::Bool,
                .default_value = false,
                .doc = "add a parameter_range constraint per limited channel of the skeleton, every frame"},
  };
  return {spec, [](const Params& p) { return std::make_unique<ConstraintsNode>(p); }};
}

// ---- retarget.holds ---------------------------------------------------------------------------
class HoldsNode final : public Node {
 public:
  explicit HoldsNode(const Params& p) : weight_(p.get<double>("weight")) {
    options_.points_a = motion::split_names(p.get<std::string>("points"));
    options_.points_b = motion::split_names(p.get<std::string>("points2"));
    options_.max_distance = p.get<double>("max_distance");
    options_.hysteresis = p.get<double>("hysteresis");
    options_.min_duration_s = p.get<double>("min_duration_s");
    options_.validate();  // a bad setting fails when the graph loads
  }

  void run(RunContext& ctx) const override {
    const retarget::HoldDetection d = retarget::detect_holds(ctx.input<motion::Motion>("motion"),
                                                             ctx.input<motion::Motion>("motion2"), options_);
    ctx.report("holds", static_cast<std::int64_t>(d.holds.size()));
    ctx.report("closest_m", d.closest);
    std::int64_t frames = 0;
    for (const retarget::HoldSpan& h : d.holds) frames += h.last_frame - h.first_frame + 1;
    ctx.report("held_frames", frames);
    if (d.holds.empty())
      ctx.log("no holds: the points come no closer than " + std::to_string(d.closest) + " m (max_distance " +
              std::to_string(options_.max_distance) + " m)");
    retarget::ConstraintSet set = retarget::hold_constraints(d, weight_);
    report_set(ctx, set);
    ctx.output("constraints", std::move(set));
  }

 private:
  retarget::HoldOptions options_;
  double weight_;
};

NodeType holds_type() {
  NodeSpec spec;
  spec.type = "retarget.holds";
  spec.doc =
      "Finds holds between two characters (Gleicher 1998 §7.3: dancers' hands that stay connected): spans "
      "where "
      "a point of the first and a point of the second stay within max_distance, and emits them as distance "
      "constraints keeping, every frame, the distance the source had.";
  spec.inputs = {{"motion", "kg.Motion", true, "the first character's source clip (character 0)"},
                 {"motion2", "kg.Motion", true,
                  "the second character's source clip (character 1), same frames and rate"}};
  spec.outputs = {kConstraintsOut};
  spec.params = {
      ParamSpec{
          .name = "points",
          .type = ParamType::String,
          .default_value = std::string("lHand, rHand"),
          .doc = "comma-separated points of the first character: 'Joint', 'Joint/end' or 'Joint[x y z]'"},
      ParamSpec{.name = "points2",
                .type = ParamType::String,
                .default_value = std::string("lHand, rHand"),
                .doc = "the same for the second character"},
      ParamSpec{.name = "max_distance",
                .type = ParamType::Float,
                .default_value = 0.15,
                .doc = "m: points this close are holding",
                .min = 1e-6,
                .max = 10.0},
      ParamSpec{.name = "hysteresis",
                .type = ParamType::Float,
                .default_value = 1.25,
                .doc = "a hold ends beyond max_distance x this",
                .min = 1.0,
                .max = 10.0},
      ParamSpec{.name = "min_duration_s",
                .type = ParamType::Float,
                .default_value = 0.2,
                .doc = "shorter holds are dropped, seconds",
                .min = 0.0,
                .max = 100.0},
      ParamSpec{.name = "weight",
                .type = ParamType::Float,
                .default_value = 1.0,
                .doc = "row weight of the hold constraints",
                .min = 1e-6,
                .max = 1e6},
  };
  return {spec, [](const Params& p) { return std::make_unique<HoldsNode>(p); }};
}

// ---- retarget.merge_constraints --------------------------------------------------------------
class MergeNode final : public Node {
 public:
  explicit MergeNode(const Params&) {}
  void run(RunContext& ctx) const override {
    retarget::ConstraintSet set = ctx.input<retarget::ConstraintSet>("a");
    for (const char* port : {"b", "c", "d"})
      if (ctx.has_input(port)) retarget::merge_constraints(set, ctx.input<retarget::ConstraintSet>(port));
    report_set(ctx, set);
    ctx.output("constraints", std::move(set));
  }
};

NodeType merge_type() {
  NodeSpec spec;
  spec.type = "retarget.merge_constraints";
  spec.doc = "Concatenates up to four constraint sets (a, then b, c, d when connected).";
  spec.inputs = {{"a", "kg.Constraints", true, "first set"},
                 {"b", "kg.Constraints", false, "second set"},
                 {"c", "kg.Constraints", false, "third set"},
                 {"d", "kg.Constraints", false, "fourth set"}};
  spec.outputs = {kConstraintsOut};
  return {spec, [](const Params& p) { return std::make_unique<MergeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> retarget_constraint_node_types() {
  return {footplants_type(), constraints_type(), holds_type(), merge_type()};
}

}  // namespace kg
