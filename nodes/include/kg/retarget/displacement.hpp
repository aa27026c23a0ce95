// The displacement map of Gleicher 1998 §3.7: m(t) = m1(t) + d(t), where each channel's
// displacement d_c is a uniform cubic B-spline whose control points lie every k_c frames. A
// spline with key spacing k cannot represent frequencies above about 1 / (2k) cycles per
// frame, so the spacing bounds the frequency content the adaptation adds.
//
// Knot layout (one channel, spacing k frames, a clip of F frames): the curve is made of
// S = max(1, ceil((F - 1) / k)) uniform segments, segment i covering frames [i k, (i + 1) k];
// it has S + 3 control points, control j sitting at frame (j - 1) k, i.e. one control before
// frame 0 and up to two past the last frame (extra controls beyond the ends, no clamping, so
// the ends are as free and as smooth as the middle). Frame f lies in segment
// i = min(floor(f / k), S - 1) at s = f / k - i in [0, 1], and only controls i .. i + 3 are
// non-zero there, with the cubic B-spline weights of kg/motion/bspline.hpp.
//
//   DisplacementLayout layout(frames, spacing.frames_per_key);        // one entry per channel
//   Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.unknown_count());
//   x[layout.unknown(channel, j)] = 0.01;                              // channel-major storage
//   motion::FrameMatrix d = layout.sample(x);                          // frames x channels
#pragma once

#include <vector>

#include <Eigen/Core>

#include "kg/motion/bspline.hpp"
#include "kg/motion/motion.hpp"

namespace kg::retarget {

// The controls of every channel of one character, stored channel-major: channel c's controls
// are x[offset(c) .. offset(c) + control_count(c)). Immutable after construction.
class DisplacementLayout {
 public:
  DisplacementLayout() = default;
  // spacing[c] frames between channel c's controls (>= 1). Throws std::invalid_argument for
  // frames < 1 or a spacing < 1.
  DisplacementLayout(int frames, std::vector<int> spacing);

  int frames() const { return frames_; }
  int channel_count() const { return static_cast<int>(spacing_.size()); }
  int spacing(int channel) const { return spacing_[static_cast<std::size_t>(channel)]; }
  int control_count(int channel) const { return controls_[static_cast<std::size_t>(channel)]; }
  int offset(int channel) const { return offset_[static_cast<std::size_t>(channel)]; }
  int unknown(int channel, int control) const { return offset(channel) + control; }
  int unknown_count() const { return total_; }
  // Frame at which control j of the channel sits ((j - 1) k; may lie outside the clip).
  int control_frame(int channel, int control) const { return (control - 1) * spacing(channel); }
  // Basis of `channel` at `frame` (looked up, no trigonometry or division per call).
  const motion::BasisAt& basis(int channel, int frame) const;

  // d(frame, channel) for all frames: frames x channels. x has unknown_count() entries.
  motion::FrameMatrix sample(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  // m1 + d: the displaced motion's values (m1 is frames x channels).
  motion::FrameMatrix apply(const motion::FrameMatrix& m1, const Eigen::Ref<const Eigen::VectorXd>& x) const;
  // Least-squares controls whose spline best fits `values` (frames x channels) — the
  // projection onto the representable signals, used by tests to measure what a spacing keeps.
  Eigen::VectorXd fit(const motion::FrameMatrix& values, double damping = 1e-12) const;

 private:
  int frames_ = 0;
  int total_ = 0;
  std::vector<int> spacing_, controls_, offset_;
  // Basis tables per distinct spacing: basis_[spacing_slot_[c]][frame].
  std::vector<int> spacing_slot_;
  std::vector<std::vector<motion::BasisAt>> basis_;
};

}  // namespace kg::retarget
