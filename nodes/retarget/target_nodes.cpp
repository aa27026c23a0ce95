// retarget.target, retarget.initial_estimate and retarget.key_spacing: thin adapters over
// target.hpp, initial_estimate.hpp and key_spacing.hpp.
#include <cmath>
#include <memory>

#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/target.hpp"

namespace kg {
namespace {

using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;

class TargetNode final : public graph::Node {
 public:
  explicit TargetNode(const Params& p) : scale_(p.get<double>("scale")), path_(p.get<std::string>("target")) {
    if (!std::isfinite(scale_) || !(scale_ > 0))
      throw std::invalid_argument("scale " + text::significant(scale_) + ": expected a finite number > 0");
  }

  void run(RunContext& ctx) const override {
    const auto& m = ctx.input<motion::Motion>("motion");
    retarget::LoadedTarget t;
    if (path_.empty()) {
      t.target = retarget::uniform_target(m.skeleton, scale_);
      t.kind = "uniform";
    } else {
      t = retarget::load_target(m.skeleton, path_);
      if (scale_ != 1.0) {
        const std::string note =
            "scale " + text::significant(scale_) + " ignored: the target file " + path_ + " sets the lengths";
        t.notes.push_back(note);
      }
    }
    for (const std::string& note : t.notes) ctx.log(note);
    const Eigen::VectorXd f = t.target.joint_factors(0.0);
    ctx.report("kind", t.kind);
    ctx.report("joints", static_cast<std::int64_t>(m.skeleton->joint_count()));
    ctx.report("overall_scale", t.target.overall_scale(0.0));
    ctx.report("min_factor", f.size() ? f.minCoeff() : 1.0);
    ctx.report("max_factor", f.size() ? f.maxCoeff() : 1.0);
    if (t.target.morphing()) {
      ctx.report("morph_keys", static_cast<std::int64_t>(t.target.key_times.size()));
      ctx.report("overall_scale_end", t.target.overall_scale(t.target.key_times.back()));
    }
    if (!t.notes.empty()) {
      std::string all;
      for (const std::string& n : t.notes) all += (all.empty() ? "" : "\n") + n;
      ctx.report("notes", all);
    }
    ctx.output("target", std::move(t.target));
  }

 private:
  double scale_;
  std::string path_;
};

class InitialEstimateNode final : public graph::Node {
 public:
  explicit InitialEstimateNode(const Params& p) {
    options_.smooth_seconds = p.get<double>("smooth_s");
    options_.validate();  // a bad setting fails when the graph loads
  }

  void run(RunContext& ctx) const override {
    const auto& m = ctx.input<motion::Motion>("motion");
    const auto& target = ctx.input<retarget::Target>("target");
    const retarget::ConstraintSet* set =
        ctx.has_input("constraints") ? &ctx.input<retarget::ConstraintSet>("constraints") : nullptr;
    retarget::ConstraintKindTable table;
    if (set != nullptr) table = retarget::kinds_for(*set, ctx);
    const retarget::KindFinder finder = [&](const std::string& name) { return table.find(name); };
    retarget::InitialEstimate e = retarget::initial_estimate(m, target, set, finder, options_);
    double mean = 0, worst = 0;
    for (Eigen::Index f = 0; f < e.shift.rows(); ++f) {
      const double n = e.shift.row(f).norm();
      mean += n;
      worst = std::max(worst, n);
    }
    if (e.shift.rows() > 0) mean /= static_cast<double>(e.shift.rows());
    const auto [lo, hi] = std::minmax_element(e.scale.begin(), e.scale.end());
    ctx.report("scale", e.scale.empty() ? target.overall_scale(0.0) : e.scale.front());
    if (target.morphing() && !e.scale.empty()) {
      ctx.report("scale_min", *lo);
      ctx.report("scale_max", *hi);
    }
    ctx.report("mean_shift_m", mean);
    ctx.report("max_shift_m", worst);
    ctx.report("constrained_frames", static_cast<std::int64_t>(e.constrained_frames));
    ctx.report("rows_used", static_cast<std::int64_t>(e.rows_used));
    ctx.report("rows_ignored", static_cast<std::int64_t>(e.rows_ignored));
    std::string axes;
    for (int a = 0; a < 3; ++a)
      if (e.axes_fixed[static_cast<std::size_t>(a)])
        axes += (axes.empty() ? "" : " ") + std::string(1, "xyz"[a]);
    ctx.report("axes_fixed", axes.empty() ? std::string("none") : axes);
    for (const std::string& n : e.notes) ctx.log(n);
    ctx.output("motion", std::move(e.motion));
  }

 private:
  retarget::InitialEstimateOptions options_;
};

class KeySpacingNode final : public graph::Node {
 public:
  explicit KeySpacingNode(const Params& p) {
    options_.threshold = p.get<double>("threshold");
    options_.spacing = static_cast<int>(p.get<std::int64_t>("spacing"));
    options_.groups = p.get<std::string>("groups");
    options_.validate();  // a bad setting (or bad groups text) fails when the graph loads
  }

  void run(RunContext& ctx) const override {
    const auto& m = ctx.input<motion::Motion>("motion");
    std::vector<retarget::KeyGroupChoice> details;
    retarget::KeySpacing keys = retarget::choose_key_spacing(m, options_, &details);
    for (std::size_t g = 0; g < details.size(); ++g) {
      const retarget::KeyGroupChoice& c = details[g];
      const std::string prefix = g == 0 ? std::string() : "group" + std::to_string(g) + "_";
      if (c.channels == 0) continue;
      ctx.report(prefix + "spacing", static_cast<std::int64_t>(c.spacing));
      ctx.report(prefix + "channels", static_cast<std::int64_t>(c.channels));
      if (c.automatic) {
        for (std::size_t k = 0; k < c.energy.fraction.size(); ++k)
          ctx.report(prefix + "level" + std::to_string(k) + "_fraction", c.energy.fraction[k]);
        ctx.report(prefix + "level", static_cast<std::int64_t>(c.level));
      }
    }
    ctx.report("reason", keys.reason);
    ctx.output("keys", std::move(keys));
  }

 private:
  retarget::KeySpacingOptions options_;
};

class ConstraintsOnTargetNode final : public graph::Node {
 public:
  explicit ConstraintsOnTargetNode(const Params& p)
      : character_(static_cast<int>(p.get<std::int64_t>("character"))) {}
  void run(RunContext& ctx) const override {
    const auto& constraints = ctx.input<retarget::ConstraintSet>("constraints");
    const auto& target = ctx.input<retarget::Target>("target");
    if (target.morphing() && !ctx.has_input("motion"))
      throw std::invalid_argument(
          "a morphing target scales points per frame: connect the clip to 'motion' (its "
          "frame rate gives each frame's time)");
    const double fps = ctx.has_input("motion") ? ctx.input<motion::Motion>("motion").fps : 0.0;
    ctx.output("constraints", retarget::constraints_on_target(constraints, target, character_, fps));
  }

 private:
  int character_;
};

NodeType constraints_on_target_type() {
  NodeSpec spec{
      .type = "retarget.constraints_on_target",
      .version = 1,
      .doc =
          "Moves constraints measured on the source character onto the target: the offset of every point "
          "fixed on a segment (a heel on the foot) is scaled by its joint's factor, as End Sites are; on a "
          "morphing target, by the factor at each sample's frame. Targets (positions, distances) are kept: "
          "they belong to the world.",
      .inputs =
          {{"constraints", "kg.Constraints", true, "constraints with points in source segments"},
           {"target", "kg.Target", true, "the target character"},
           {"motion", "kg.Motion", false,
            "the clip the constraints' frames belong to (required for a morphing target: frame times)"}},
      .outputs = {{"constraints", "kg.Constraints", true, "the same constraints with points on the target"}},
      .params = {{.name = "character",
                  .type = ParamType::Int,
                  .default_value = std::int64_t{0},
                  .doc = "which character's points move (0 first, 1 second)",
                  .min = 0.0,
                  .max = 1.0}}};
  return {spec, [](const Params& p) { return std::make_unique<ConstraintsOnTargetNode>(p); }};
}

NodeType target_type() {
  NodeSpec spec;
  spec.type = "retarget.target";
  spec.version = 1;
  spec.doc =
      "The character to retarget to: the motion's skeleton with other segment lengths, as a uniform `scale`, "
      "or a "
      "`target` file: YAML of per-bone factors (bones:, joint-name regex (RE2) matched against the whole "
      "name, "
      "first match "
      "wins), absolute lengths (lengths:) or keyframed factors (morph:), or a .bvh/.asf skeleton of the same "
      "structure (its offsets are taken; axes and channels stay the source's).";
  spec.inputs = {{"motion", "kg.Motion", true, "the source clip (its skeleton is the source character)"}};
  spec.outputs = {{"target", "kg.Target", true, "the target character (constant or morphing)"}};
  ParamSpec scale{
      "scale", ParamType::Float, 1.0,
      "uniform length factor, used when `target` is \"\" (ignored, and said so, when a file is given)"};
  scale.min = 1e-6;
  scale.max = 1e6;
  ParamSpec target{
      "target", ParamType::InputPath, std::string{},
      "\"\" for the uniform scale, or a .yaml/.yml of factors, lengths or morph keys, or a .bvh/.asf "
      "skeleton"};
  spec.params = {scale, target};
  return {spec, [](const Params& p) { return std::make_unique<TargetNode>(p); }};
}

NodeType initial_estimate_type() {
  NodeSpec spec;
  spec.type = "retarget.initial_estimate";
  spec.version = 1;
  spec.doc =
      "Initial estimate m1 (Gleicher 1998, 3.8): the root translation scaled by the target's overall scale "
      "(per "
      "frame changes scaled and summed when morphing), then shifted per frame by the averaged constraint "
      "displacements on the axes constraints fix, interpolated over unconstrained frames and low-pass "
      "filtered. "
      "The output motion is on the target skeleton.";
  spec.inputs = {
      {"motion", "kg.Motion", true, "the source clip"},
      {"target", "kg.Target", true, "the target character (of the clip's structure)"},
      {"constraints", "kg.Constraints", false, "constraints whose fixed positions recentre the motion"}};
  spec.outputs = {{"motion", "kg.Motion", true, "m1, on target.skeleton"}};
  ParamSpec smooth{"smooth_s", ParamType::Float, 0.15,
                   "Gaussian sigma of the low-pass on the added translation, seconds (0: none)"};
  smooth.min = 0;
  smooth.max = 60;
  spec.params = {smooth};
  return {spec, [](const Params& p) { return std::make_unique<InitialEstimateNode>(p); }};
}

NodeType key_spacing_type() {
  NodeSpec spec;
  spec.type = "retarget.key_spacing";
  spec.version = 1;
  spec.doc =
      "Key spacing of the displacement map (Gleicher 1998, 3.7): a band-pass pyramid of the clip's channels; "
      "the "
      "spacing is 2^k frames (clamped to 2..8) for the lowest level k whose share of the band energy exceeds "
      "`threshold`; or set by hand, for all channels or per group of joints.";
  spec.inputs = {{"motion", "kg.Motion", true, "the source clip"}};
  spec.outputs = {{"keys", "kg.KeySpacing", true, "frames per key for every channel, and why"}};
  ParamSpec threshold{"threshold", ParamType::Float, 0.1,
                      "fraction of the band energy a level must exceed to set the spacing"};
  threshold.min = 1e-6;
  threshold.max = 0.999;
  ParamSpec spacing{"spacing", ParamType::Int, std::int64_t{0},
                    "frames per key for channels in no group: 0 = automatic, else e.g. 2, 4, 8"};
  spacing.min = 0;
  spacing.max = 100000;
  ParamSpec groups{
      "groups", ParamType::String, std::string{},
      "per-group spacings: 'regex=spacing' items separated by ';', regex (RE2) searched in joint names, "
      "first match wins, 0 = automatic for that group (e.g. \"arm|hand|Arm|Hand=2\")"};
  spec.params = {threshold, spacing, groups};
  return {spec, [](const Params& p) { return std::make_unique<KeySpacingNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> retarget_target_node_types() {
  return {target_type(), constraints_on_target_type(), initial_estimate_type(), key_spacing_type()};
}

}  // namespace kg
