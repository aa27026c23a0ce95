// retime.playback: a thin adapter over retimed_motion (playback.hpp).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>

#include "kg/base/text.hpp"
#include "kg/retime/nodes.hpp"
#include "kg/retime/playback.hpp"

namespace kg::retime {
namespace {

class PlaybackNode final : public graph::Node {
 public:
  explicit PlaybackNode(const graph::Params& p) : fps_(p.get<double>("fps")) {}
  void run(graph::RunContext& ctx) const override {
    const motion::Motion& clip = ctx.input<motion::Motion>("motion");
    const TimeWarp& warp = ctx.input<TimeWarp>("warp");
    const double fps = fps_ > 0 ? fps_ : clip.fps;
    // The clip the warp was solved on may be the same clip at a coarser rate, up to one of its
    // frames shorter.
    double slack = -1;
    if (ctx.has_input("source"))
      slack = std::max(0.5 / clip.fps, 1.0 / ctx.input<motion::Motion>("source").fps);
    motion::Motion out = retimed_motion(clip, warp, fps, slack);
    ctx.report("fps", fps);
    ctx.report("frames", static_cast<std::int64_t>(out.frame_count()));
    ctx.output("motion", std::move(out));
  }

 private:
  double fps_;
};

}  // namespace

graph::NodeType playback_node_type() {
  graph::NodeSpec spec{
      .type = "retime.playback",
      .version = 1,
      .doc =
          "Plays a clip through a retiming (retime.retime's warp, p(t) in source seconds, so any rate of "
          "the clip plays it): frame k at k / fps is the clip's pose at p(k / fps), positions linear and "
          "rotations slerped. A retiming worked out at 30 Hz thus writes a 120 Hz capture at 120 Hz, with "
          "its own detail; the capture's last frames past its 30 Hz copy's end play at the warp's end speed.",
      .inputs = {{"motion", "kg.Motion", true, "the clip to play, at any rate"},
                 {"warp", "kg.TimeWarp", true, "the retiming (retime.retime)"},
                 {"source", "kg.Motion", false,
                  "the clip the warp was solved on, when at another rate (it may end up to one of its "
                  "frames before `motion`)"}},
      .outputs = {{"motion", "kg.Motion", true, "the retimed clip at `fps`"}},
      .params = {{.name = "fps",
                  .type = graph::ParamType::Float,
                  .default_value = 0.0,
                  .doc = "frame rate written; 0: the clip's",
                  .min = 0.0,
                  .max = 1e5}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<PlaybackNode>(p); }};
}

}  // namespace kg::retime
