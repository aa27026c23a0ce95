// retarget.at_rate: a thin adapter over result_at_rate and constraints_at_rate (at_rate.hpp), then
// solve_per_frame_ik (per_frame_ik.hpp) to hold the constraints at the rate written.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retarget/at_rate.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/per_frame_ik.hpp"

namespace kg::retarget {
namespace {

void log_left_out(graph::RunContext& ctx, const ConstraintSet& solved, const ConstraintSet& written,
                  double fps) {
  // `written` keeps `solved`'s order, less the constraints left out.
  std::size_t next = 0;
  std::string left_out;
  int count = 0;
  for (const Constraint& c : solved.constraints)
    if (next < written.constraints.size() && written.constraints[next].label == c.label &&
        written.constraints[next].kind == c.kind)
      ++next;
    else {
      ++count;
      if (count <= 5) left_out += (left_out.empty() ? "'" : ", '") + c.label + "'";
    }
  if (count == 0) return;
  ctx.log(std::to_string(count) + " constraint" + (count == 1 ? "" : "s") + " (" + left_out +
          (count > 5 ? ", ..." : "") + ") span less than one frame at " + text::significant(fps) +
          " fps: not checked at the rate written");
}

class AtRateNode final : public graph::Node {
 public:
  explicit AtRateNode(const graph::Params& p) : hold_(p.get<bool>("hold")) {
    hold_options_.tolerance = p.get<double>("hold_tolerance_mm") / 1000.0;
    hold_options_.validate();
  }
  void run(graph::RunContext& ctx) const override {
    const motion::Motion& clip = ctx.input<motion::Motion>("motion");
    const motion::Motion& solve_source = ctx.input<motion::Motion>("source");
    ResultAtRate r = result_at_rate(clip, solve_source, ctx.input<motion::Motion>("initial"),
                                    ctx.input<motion::Motion>("result"), ctx.input<Target>("target"));
    ctx.report("fps", clip.fps);
    ctx.report("frames", static_cast<std::int64_t>(clip.frame_count()));
    ctx.report("solve_fps", solve_source.fps);
    if (clip.fps != solve_source.fps)
      ctx.log("the result solved at " + text::significant(solve_source.fps) + " fps is written at " +
              text::significant(clip.fps) + " fps (" + std::to_string(clip.frame_count()) +
              " frames): the source at that rate plus the solve's displacement, a spline in time");
    if (ctx.has_input("constraints")) {
      const ConstraintSet& solved = ctx.input<ConstraintSet>("constraints");
      ConstraintSet written = constraints_at_rate(solved, solve_source.fps, clip.fps, clip.frame_count());
      log_left_out(ctx, solved, written, clip.fps);
      if (clip.fps != solve_source.fps) hold(ctx, r, written);
      ctx.output("constraints", std::move(written));
    }
    ctx.output("initial", std::move(r.initial));
    ctx.output("motion", std::move(r.result));
  }

 private:
  void hold(graph::RunContext& ctx, ResultAtRate& r, const ConstraintSet& written) const {
    if (!hold_) {
      ctx.log(
          "hold: false: the frames written keep the spline's displacement (constraints not held between "
          "the solve's frames)");
      return;
    }
    const ConstraintKindTable kinds = kinds_for(written, ctx);
    PerFrameIkResult held = solve_per_frame_ik(
        r.result, written, [&](const std::string& n) { return kinds.find(n); }, hold_options_);
    ctx.report("frames_held", static_cast<std::int64_t>(held.frames_constrained));
    ctx.report("frames_held_unmet", static_cast<std::int64_t>(held.frames_unmet));
    ctx.report("hold_worst_mm", 1000.0 * held.worst_violation);
    if (held.frames_constrained > 0)
      ctx.log("hold: the constraints held at the rate written by per-frame IK from the spline's result (" +
              held.message + ")");
    r.result = std::move(held.motion);
  }

  bool hold_;
  PerFrameIkOptions hold_options_;
};

}  // namespace

graph::NodeType at_rate_node_type() {
  graph::NodeSpec spec{
      .type = "retarget.at_rate",
      .version = 1,
      .doc =
          "A retargeting solved at one rate (retarget.spacetime at `fps`), written at another: the "
          "source at the rate written, scaled as the initial estimate scales it, plus the solve's "
          "displacement (result minus the scaled source at the solve's rate), a C2 cubic spline "
          "through the solve's frames. Exact at every solve frame; between them the finer rate "
          "keeps the source's own detail. With the same rate and frames the result passes unchanged. "
          "The constraints, when wired, come out at the rate written, so metrics check what was held at "
          "every frame written; at a rate other than the solve's they are held there by per-frame IK "
          "(param hold), since between solve frames the spline meets them only approximately.",
      .inputs = {{"motion", "kg.Motion", true, "the source clip at the rate to write, on its own skeleton"},
                 {"source", "kg.Motion", true, "the same clip at the solve's rate (what the solve adapted)"},
                 {"initial", "kg.Motion", true, "the solve's initial estimate (retarget.initial_estimate)"},
                 {"result", "kg.Motion", true, "the solve's result (retarget.spacetime)"},
                 {"target", "kg.Target", true, "the target character"},
                 {"constraints", "kg.Constraints", false, "the solve's constraints, at the solve's rate"}},
      .outputs = {{"motion", "kg.Motion", true, "the result at `motion`'s rate, on the target skeleton"},
                  {"initial", "kg.Motion", true, "the initial estimate at that rate (for retarget.metrics)"},
                  {"constraints", "kg.Constraints", false,
                   "the solve's constraints at that rate, every frame of their time sampled (for "
                   "retarget.metrics)"}},
      .params = {{.name = "hold",
                  .type = graph::ParamType::Bool,
                  .default_value = true,
                  .doc = "at a rate other than the solve's, every constrained frame written is solved to the "
                         "constraints at that rate by per-frame IK, damped towards the spline's result "
                         "(false: the frames keep the spline's displacement, which between two solve frames "
                         "meets the constraints only as closely as the source moves like a spline)"},
                 {.name = "hold_tolerance_mm",
                  .type = graph::ParamType::Float,
                  .default_value = 0.1,
                  .doc = "a frame held is met when every row is within this, mm (as retarget.per_frame_ik's)",
                  .min = 0.0}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<AtRateNode>(p); }};
}

}  // namespace kg::retarget
