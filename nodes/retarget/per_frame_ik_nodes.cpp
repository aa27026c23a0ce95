// retarget.per_frame_ik: a thin adapter over solve_per_frame_ik (per_frame_ik.hpp).
#include <cstdint>
#include <memory>

#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/per_frame_ik.hpp"

namespace kg::retarget {
namespace {

using graph::ParamType;

class PerFrameIkNode final : public graph::Node {
 public:
  explicit PerFrameIkNode(const graph::Params& p) {
    options_.epsilon = p.get<double>("epsilon");
    options_.max_iterations = static_cast<int>(p.get<std::int64_t>("iterations"));
    options_.tolerance = p.get<double>("tolerance_mm") / 1000.0;
    options_.validate();  // a bad setting fails when the graph loads
  }
  void run(graph::RunContext& ctx) const override {
    const motion::Motion& initial = ctx.input<motion::Motion>("motion");
    const ConstraintSet& set = ctx.input<ConstraintSet>("constraints");
    const ConstraintKindTable kinds = kinds_for(set, ctx);
    PerFrameIkResult r = solve_per_frame_ik(
        initial, set, [&](const std::string& n) { return kinds.find(n); }, options_);
    ctx.report("seconds", r.seconds);
    ctx.report("iterations", static_cast<std::int64_t>(r.iterations));
    ctx.report("frames_constrained", static_cast<std::int64_t>(r.frames_constrained));
    ctx.report("frames_unmet", static_cast<std::int64_t>(r.frames_unmet));
    ctx.report("worst_violation_mm", 1000.0 * r.worst_violation);
    if (r.frames_unmet > 0) ctx.log("per-frame IK: " + r.message);
    ctx.output("seconds", r.seconds);
    ctx.output("motion", std::move(r.motion));
  }

 private:
  PerFrameIkOptions options_;
};

}  // namespace

graph::NodeType per_frame_ik_node_type() {
  graph::NodeSpec spec{
      .type = "retarget.per_frame_ik",
      .version = 1,
      .doc =
          "The per-frame inverse kinematics baseline (Gleicher 1998 3.1): every constrained frame "
          "solved on its own by Levenberg-Marquardt from the initial motion's frame, minimising "
          "the constraint rows plus epsilon x the sensitivity-weighted change (the spacetime "
          "solver's damping); inequality rows through an active set. A sample is solved at the "
          "latest frame it reads, its earlier frames fixed as already solved (forward in time), "
          "so non-skid plants hold from their first frame. Frames without constraints keep the "
          "initial motion: the snaps where constraints switch on are the point of the comparison.",
      .inputs = {{"motion", "kg.Motion", true, "the initial estimate on the target skeleton"},
                 {"constraints", "kg.Constraints", true, "the constraints (one character)"}},
      .outputs = {{"motion", "kg.Motion", true, "the initial motion with each constrained frame solved"},
                  {"seconds", "kg.Scalar", true, "wall time of the solve, s (for retarget.metrics)"}},
      .params = {{.name = "epsilon",
                  .type = ParamType::Float,
                  .default_value = 1e-4,
                  .doc = "damping weight of the sensitivity-weighted change (as retarget.spacetime's)",
                  .min = 0.0},
                 {.name = "iterations",
                  .type = ParamType::Int,
                  .default_value = std::int64_t{50},
                  .doc = "Levenberg-Marquardt iterations per frame, at most",
                  .min = 1.0,
                  .max = 10000.0},
                 {.name = "tolerance_mm",
                  .type = ParamType::Float,
                  .default_value = 0.1,
                  .doc = "a frame is met when every row is within this, mm (channel rows: 1e-3 rad per mm)",
                  .min = 0.0}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<PerFrameIkNode>(p); }};
}

}  // namespace kg::retarget
