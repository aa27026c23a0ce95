// The example plugin: node `filter.lowpass`, a zero-phase low-pass filter over a motion's channel
// curves. A thin adapter over filter.hpp; built as lib/kinegraph/plugins/kg_lowpass.so and loaded
// at run time (graph file: `plugins: [kg_lowpass]`), never linked into the host.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter.hpp"
#include "kg/graph/plugin_abi.hpp"
#include "kg/motion/filters.hpp"
#include "kg/motion/nodes.hpp"

namespace kg::lowpass {
namespace {

using graph::NodeSpec;
using graph::Params;
using graph::ParamType;
using motion::Motion;

enum class Channels { All, Rotations, Positions };

NodeSpec lowpass_spec() {
  return {
      .type = "filter.lowpass",
      .version = 1,
      .doc =
          "Zero-phase low-pass filter of every selected channel curve of a motion. butterworth: the "
          "digital Butterworth filter (bilinear transform, prewarped) run forward and backward, so the "
          "response is its magnitude squared: no phase lag, effective order 2 x order, cutoff_hz passed "
          "at half amplitude (-6 dB). gaussian: a Gaussian kernel, by default of the width that also "
          "passes cutoff_hz at half amplitude. Both extend the ends by odd reflection (as "
          "scipy.signal.filtfilt does): constants stay exactly constant and lines straight, with no edge "
          "transient; as in scipy the first and last frames are kept as they are. Rotation "
          "channels are unwrapped (2 pi jumps removed) before filtering and put back on the input's "
          "branch frame by frame after; Euler-angle flips other than 2 pi jumps are not detected.",
      .inputs = {{"motion", "kg.Motion", true, "the clip to smooth"}},
      .outputs = {{"motion", "kg.Motion", true, "the smoothed clip: same skeleton, frames and rate"}},
      .params =
          {{.name = "method",
            .type = ParamType::Enum,
            .default_value = std::string("butterworth"),
            .doc = "butterworth (forward-backward IIR) or gaussian (kernel)",
            .choices = {"butterworth", "gaussian"}},
           {.name = "cutoff_hz",
            .type = ParamType::Float,
            .default_value = 6.0,
            .doc = "Hz, > 0 and below the Nyquist frequency (half the motion's fps): the frequency passed at "
                   "half amplitude",
            .min = 0.0},
           {.name = "order",
            .type = ParamType::Int,
            .default_value = std::int64_t{2},
            .doc = "butterworth: order of one pass, 2 or 4 (forward-backward doubles it to 4 or 8)",
            .min = 2.0,
            .max = 4.0},
           {.name = "sigma_frames",
            .type = ParamType::Float,
            .default_value = 0.0,
            .doc = "gaussian: kernel standard deviation in frames; 0 derives it from cutoff_hz "
                   "(sigma = fps * sqrt(ln 2 / 2) / (pi cutoff_hz))",
            .min = 0.0,
            .max = 1e5},
           {.name = "channels",
            .type = ParamType::Enum,
            .default_value = std::string("all"),
            .doc = "which channels to filter: all, rotations (radians) or positions (metres)",
            .choices = {"all", "rotations", "positions"}}},
  };
}

class LowpassNode final : public graph::Node {
 public:
  explicit LowpassNode(const Params& p)
      : gaussian_(p.get<std::string>("method") == "gaussian"),
        cutoff_hz_(p.get<double>("cutoff_hz")),
        order_(static_cast<int>(p.get<std::int64_t>("order"))),
        sigma_frames_(p.get<double>("sigma_frames")) {
    const std::string& channels = p.get<std::string>("channels");
    channels_ = channels == "rotations"   ? Channels::Rotations
                : channels == "positions" ? Channels::Positions
                                          : Channels::All;
    if (!(cutoff_hz_ > 0)) throw std::invalid_argument("cutoff_hz must be greater than 0");
    if (order_ != 2 && order_ != 4) {
      throw std::invalid_argument("order must be 2 or 4, got " + std::to_string(order_));
    }
    if (!gaussian_ && sigma_frames_ != 0) {
      throw std::invalid_argument("sigma_frames applies to method gaussian only");
    }
  }

  void run(graph::RunContext& ctx) const override {
    const Motion& in = ctx.input<Motion>("motion");
    if (!in.skeleton) throw std::invalid_argument("the motion has no skeleton");
    if (in.values.cols() != in.skeleton->channel_count()) {
      throw std::invalid_argument("the motion has " + std::to_string(in.values.cols()) +
                                  " channels per frame but its skeleton declares " +
                                  std::to_string(in.skeleton->channel_count()));
    }
    const int frames = in.frame_count();
    std::vector<Biquad> sections;
    int padding = 0;
    double sigma = sigma_frames_;
    if (gaussian_) {
      if (sigma == 0) sigma = gaussian_sigma_for_cutoff(cutoff_hz_, in.fps);
    } else {
      sections = butterworth_lowpass(order_, cutoff_hz_, in.fps);
      padding = filtfilt_padding(sections);
    }

    // Column-major, so that each channel's curve is contiguous while it is filtered.
    Eigen::MatrixXd curves = in.values;
    FilterScratch scratch;
    std::int64_t filtered = 0;
    for (const motion::Joint& joint : in.skeleton->joints()) {
      for (std::size_t i = 0; i < joint.channels.size(); ++i) {
        const bool rotation = motion::is_rotation(joint.channels[i].kind);
        if ((channels_ == Channels::Rotations && !rotation) ||
            (channels_ == Channels::Positions && rotation)) {
          continue;
        }
        const std::span<double> curve(curves.col(joint.first_channel + static_cast<int>(i)).data(),
                                      static_cast<std::size_t>(frames));
        const std::vector<int> turns = rotation ? motion::unwrap_angles(curve) : std::vector<int>{};
        const bool unwrapped = std::any_of(turns.begin(), turns.end(), [](int t) { return t != 0; });
        if (gaussian_) {
          gaussian_smooth(curve, sigma);
        } else {
          filtfilt(sections, padding, curve, scratch);
        }
        if (unwrapped) {  // back on the input's branch, frame by frame
          for (int f = 0; f < frames; ++f) curve[f] -= 2 * std::numbers::pi * turns[f];
        }
        ++filtered;
      }
    }
    Motion out;
    out.skeleton = in.skeleton;
    out.values = curves;
    out.fps = in.fps;
    out.name = in.name;
    ctx.report("channels_filtered", filtered);
    ctx.report("frames", std::int64_t{frames});
    if (gaussian_) {
      ctx.report("sigma_frames", sigma);
    } else {
      ctx.report("effective_order", std::int64_t{2 * order_});
      ctx.report("padding_frames", std::int64_t{padding});
    }
    ctx.output("motion", std::move(out));
  }

 private:
  bool gaussian_;
  double cutoff_hz_;
  int order_;
  double sigma_frames_;
  Channels channels_ = Channels::All;
};

graph::PluginRecord make_record() {
  graph::PluginRecord record{"kg.lowpass", "1.0.0"};
  record.nodes.push_back({lowpass_spec(), [](const Params& p) { return std::make_unique<LowpassNode>(p); }});
  return record;
}

}  // namespace
}  // namespace kg::lowpass

KG_PLUGIN(kg::lowpass::make_record)
