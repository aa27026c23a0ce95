#include "kg/retime/path.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "kg/motion/filters.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::retime {

PathDerivatives path_derivatives(const motion::Motion& motion, double smoothing) {
  motion.check();
  if (!(smoothing >= 0) || !std::isfinite(smoothing))
    throw std::invalid_argument("path derivatives: smoothing " + std::to_string(smoothing) +
                                " s (expected >= 0)");
  const motion::Skeleton& skeleton = *motion.skeleton;
  const int frames = motion.frame_count();
  const int channels = skeleton.channel_count();
  PathDerivatives d{motion::FrameMatrix::Zero(frames, channels), motion::FrameMatrix::Zero(frames, channels)};
  if (frames < 2) return d;

  // Values with rotation channels unwrapped along the clip, one curve per column.
  Eigen::MatrixXd q = motion.values;
  for (int c = 0; c < channels; ++c) {
    auto [joint, index] = skeleton.channel_owner(c);
    if (!motion::is_rotation(skeleton.joint(joint).channels[static_cast<std::size_t>(index)].kind)) continue;
    motion::unwrap_angles(std::span<double>(q.col(c).data(), static_cast<std::size_t>(frames)));
  }
  // A parabola past the ends: a ballistic flight keeps its second derivative to the last frame.
  if (smoothing * motion.fps > 0.05)
    q = motion::gaussian_smoothed(q, smoothing * motion.fps, motion::CurveEnds::Parabola);
  const double h = 1.0 / motion.fps;
  if (frames == 2) {
    d.first.row(0) = (q.row(1) - q.row(0)) / h;
    d.first.row(1) = d.first.row(0);
    return d;
  }
  for (int f = 1; f + 1 < frames; ++f) {
    d.first.row(f) = (q.row(f + 1) - q.row(f - 1)) / (2 * h);
    d.second.row(f) = (q.row(f + 1) - 2 * q.row(f) + q.row(f - 1)) / (h * h);
  }
  const int last = frames - 1;
  d.first.row(0) = (-3 * q.row(0) + 4 * q.row(1) - q.row(2)) / (2 * h);
  d.first.row(last) = (3 * q.row(last) - 4 * q.row(last - 1) + q.row(last - 2)) / (2 * h);
  if (frames >= 4) {
    d.second.row(0) = (2 * q.row(0) - 5 * q.row(1) + 4 * q.row(2) - q.row(3)) / (h * h);
    d.second.row(last) =
        (2 * q.row(last) - 5 * q.row(last - 1) + 4 * q.row(last - 2) - q.row(last - 3)) / (h * h);
  } else {
    d.second.row(0) = d.second.row(1);
    d.second.row(last) = d.second.row(1);
  }
  return d;
}

}  // namespace kg::retime
