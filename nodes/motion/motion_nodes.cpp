// Nodes of the motion library: thin adapters over its free functions (DESIGN.md 7).
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "kg/builtin_nodes.hpp"
#include "kg/motion/motion.hpp"
#include "kg/motion/nodes.hpp"
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

class FrameRangeNode final : public graph::Node {
 public:
  explicit FrameRangeNode(const graph::Params& params)
      : first_(static_cast<int>(params.get<std::int64_t>("first"))),
        last_(static_cast<int>(params.get<std::int64_t>("last"))) {
    if (last_ != -1 && last_ < first_)
      throw std::invalid_argument("last " + std::to_string(last_) + " before first " +
                                  std::to_string(first_) +
                                  " (expected first <= last, or last -1 for the clip's last frame)");
  }

  void run(graph::RunContext& ctx) const override {
    const auto& in = ctx.input<motion::Motion>("motion");
    motion::Motion out = motion::frame_range(in, first_, last_);
    ctx.report("frames_in", static_cast<std::int64_t>(in.frame_count()));
    ctx.report("frames_out", static_cast<std::int64_t>(out.frame_count()));
    ctx.output("motion", std::move(out));
  }

 private:
  int first_, last_;
};

graph::NodeType frame_range_type() {
  graph::NodeSpec spec{
      .type = "motion.frame_range",
      .version = 1,
      .doc =
          "Keeps frames `first` to `last` of a clip (0-based, inclusive), same skeleton and rate: e.g. "
          "first 1 drops the T-pose that Daz and iClone exports of the CMU clips put first.",
      .inputs = {{"motion", "kg.Motion", true, "the clip"}},
      .outputs = {{"motion", "kg.Motion", true, "its frames first to last"}},
      .params = {{.name = "first",
                  .type = graph::ParamType::Int,
                  .default_value = std::int64_t{0},
                  .doc = "first frame kept (0: the clip's first)",
                  .min = 0,
                  .max = 1e9},
                 {.name = "last",
                  .type = graph::ParamType::Int,
                  .default_value = std::int64_t{-1},
                  .doc = "last frame kept (-1: the clip's last)",
                  .min = -1,
                  .max = 1e9}},
  };
  return {spec, [](const graph::Params& p) { return std::make_unique<FrameRangeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> motion_node_types() {
  return {resample_type(), frame_range_type()};
}

}  // namespace kg
