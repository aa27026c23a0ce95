// A clip: a skeleton (shared, immutable) and a frames x channels matrix of values at a
// constant frame rate. Values follow skeleton.hpp's conventions: metres and radians.
//
//   Motion m{skeleton, Eigen::MatrixXd::Zero(frames, skeleton->channel_count()), 120.0};
//   double hip_y = m.values(f, m.skeleton->joint(0).first_channel + 1);
#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>

#include "kg/motion/skeleton.hpp"

namespace kg::motion {

// The gravity captured clips obey (m/s²): their flights, the walk-run transition, a retiming's
// ballistic phases.
inline constexpr double kEarthGravity = 9.81;

using FrameMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Motion {
  std::shared_ptr<const Skeleton> skeleton;
  FrameMatrix values;  // frames x skeleton->channel_count()
  double fps = 30.0;   // frames per second
  std::string name;    // e.g. the source file's stem

  int frame_count() const { return static_cast<int>(values.rows()); }
  double duration() const { return frame_count() > 1 ? (frame_count() - 1) / fps : 0.0; }
  // Throws std::invalid_argument when sizes disagree, fps is not positive, or a value is not finite.
  void check() const;
};

// Frames `first` to `last` of `motion` (0-based, inclusive; last -1: the clip's last frame), same
// skeleton, rate and name: e.g. without the T-pose Daz and iClone exports put first. Throws
// std::invalid_argument naming the clip's frame count for a range outside it or reversed.
Motion frame_range(const Motion& motion, int first, int last = -1);

}  // namespace kg::motion
