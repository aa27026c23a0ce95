// Nodes of the motion library: thin adapters over its free functions (DESIGN.md 7).
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "kg/builtin_nodes.hpp"
#include "kg/motion/motion.hpp"
#include "kg/motion/resample.hpp"

namespace kg {

namespace {

class ResampleNode final : public graph::Node {
 public:
  explicit ResampleNode(const graph::Params& params) : fps_(params.get<double>("fps")) {
    if (!std::isfinite(fps_) || fps_ < 0) {
      std::ostringstream s;
      s << "fps " << fps_ << ": expected a frame rate > 0, or 0 to keep the clip's";
      throw std::invalid_argument(s.str());
    }
  }

  void run(graph::RunContext& ctx) const override {
    const auto& in = ctx.input<motion::Motion>("motion");
    // fps 0 lets a graph variable switch resampling off (graphs/convert.yaml's `resample`).
    motion::Motion out = fps_ > 0 ? motion::resample(in, fps_) : in;
    ctx.report("frames_in", static_cast<std::int64_t>(in.frame_count()));
    ctx.report("frames_out", static_cast<std::int64_t>(out.frame_count()));
    ctx.report("fps_in", in.fps);
    ctx.report("fps_out", out.fps);
    ctx.report("duration_s", out.duration());
    ctx.output("motion", std::move(out));
  }

 private:
  double fps_;
};

graph::NodeType resample_type() {
  graph::NodeSpec spec{
      .type = "motion.resample",
      .version = 1,
      .doc =
          "Resamples a clip to another frame rate, keeping its duration: floor(duration * fps) + 1 frames. "
          "Positions are interpolated linearly; each joint's rotations are slerped and converted back to "
          "its own Euler order, continuous with the previous frame. Frames at times the input has are "
          "copied.",
      .inputs = {{"motion", "kg.Motion", true, "the clip (metres, radians)"}},
      .outputs = {{"motion", "kg.Motion", true, "the clip at `fps`, same skeleton and name"}},
      .params = {{.name = "fps",
                  .type = graph::ParamType::Float,
                  .default_value = 30.0,
                  .doc =
                      "new frame rate, frames per second (e.g. 30 for the paper's 120 Hz captures); 0 keeps "
                      "the clip as it is",
                  .required = true,
                  .min = 0,
                  .max = 1e5}},
  };
  return {spec, [](const graph::Params& p) { return std::make_unique<ResampleNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> motion_node_types() {
  return {resample_type()};
}

}  // namespace kg
