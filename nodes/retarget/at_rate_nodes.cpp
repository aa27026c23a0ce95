// retarget.at_rate: a thin adapter over result_at_rate (at_rate.hpp).
#include <memory>
#include <string>
#include <utility>

#include "kg/base/text.hpp"
#include "kg/retarget/at_rate.hpp"
#include "kg/retarget/nodes.hpp"

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
  explicit AtRateNode(const graph::Params&) {}
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
      ctx.output("constraints", std::move(written));
    }
    ctx.output("initial", std::move(r.initial));
    ctx.output("motion", std::move(r.result));
  }
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
          "every frame written.",
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
      .params = {}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<AtRateNode>(p); }};
}

}  // namespace kg::retarget
