// What the synthesizer tests measure, all through the motion library's own forward kinematics
// (not the synthesizer's internal pose), so they check the frames a consumer gets.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "kg/motion/kinematics.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg::synth::test {

// World transforms of every joint in every frame.
struct Kinematics {
  std::vector<std::vector<Eigen::Isometry3d>> world;  // [frame][joint]

  explicit Kinematics(const motion::Motion& m) {
    const motion::Skeleton& s = *m.skeleton;
    world.assign(static_cast<std::size_t>(m.frame_count()),
                 std::vector<Eigen::Isometry3d>(static_cast<std::size_t>(s.joint_count())));
    for (int f = 0; f < m.frame_count(); ++f)
      motion::forward_kinematics(s, m.values.row(f), world[std::size_t(f)]);
  }
  Eigen::Vector3d point(int frame, int joint, const Eigen::Vector3d& local) const {
    return world[std::size_t(frame)][std::size_t(joint)] * local;
  }
  Eigen::Vector3d joint(int frame, int joint) const {
    return world[std::size_t(frame)][std::size_t(joint)].translation();
  }
  int frames() const { return static_cast<int>(world.size()); }
};

// Points on the sole of one foot: heel, under the ball, toe tip.
struct SolePoints {
  Eigen::Vector3d heel, ball_sole, toe_tip;
  double lowest() const { return std::min({heel.y(), ball_sole.y(), toe_tip.y()}); }
};

inline SolePoints sole(const Kinematics& k, const Figure& fig, int frame, Side side) {
  return {k.point(frame, fig.foot[side], fig.heel_local),
          k.point(frame, fig.toe[side], Eigen::Vector3d(0, -fig.dims.ball_height, 0)),
          k.point(frame, fig.toe[side], fig.toe_tip_local)};
}

// Height at which a planted point sits: heel and toe tip on the floor, the ball joint and the
// ankle above it by their heights in the figure.
inline double plant_height(const Figure& fig, FootPoint p) {
  switch (p) {
    case FootPoint::Heel:
    case FootPoint::Toe:
      return 0;
    case FootPoint::Ball:
      return fig.dims.ball_height;
    case FootPoint::Ankle:
      return fig.dims.ankle_height;
  }
  return -1;
}

// Largest movement of any plant's point away from its recorded place over its frames, and the
// largest distance of a planted point from its height above the floor.
struct PlantErrors {
  double drift = 0, height = 0;
  int frames_checked = 0;
};
inline PlantErrors plant_errors(const Synthesis& s, const Kinematics& k) {
  PlantErrors e;
  for (const FootPlant& p : s.plants) {
    for (int f = p.first_frame; f <= p.last_frame; ++f) {
      const Eigen::Vector3d w = k.point(f, p.joint, p.local);
      e.drift = std::max(e.drift, (w - p.world).norm());
      e.height = std::max(e.height, std::abs(w.y() - plant_height(s.figure, p.point)));
      ++e.frames_checked;
    }
  }
  return e;
}

// Lowest height of any sole point of either foot over the clip.
inline double lowest_sole(const Synthesis& s, const Kinematics& k) {
  double low = 1e9;
  for (int f = 0; f < k.frames(); ++f)
    for (Side side : {kLeft, kRight}) low = std::min(low, sole(k, s.figure, f, side).lowest());
  return low;
}

// Per channel: the largest change between neighbouring frames, and the largest second
// difference over dt^2 (an acceleration estimate: bounded as dt shrinks only for C1 curves).
struct ChannelSmoothness {
  double max_step = 0;  // radians or metres
  int max_step_channel = -1;
  double max_accel = 0;  // units / s^2
  int max_accel_channel = -1;
};
inline ChannelSmoothness smoothness(const motion::Motion& m, bool rotations_only) {
  ChannelSmoothness r;
  const double dt = 1 / m.fps;
  for (int c = 0; c < m.skeleton->channel_count(); ++c) {
    const auto [joint, index] = m.skeleton->channel_owner(c);
    if (rotations_only && !motion::is_rotation(m.skeleton->joint(joint).channels[std::size_t(index)].kind))
      continue;
    for (int f = 1; f < m.frame_count(); ++f) {
      const double step = std::abs(m.values(f, c) - m.values(f - 1, c));
      if (step > r.max_step) {
        r.max_step = step;
        r.max_step_channel = c;
      }
      if (f + 1 < m.frame_count()) {
        const double acc = std::abs(m.values(f + 1, c) - 2 * m.values(f, c) + m.values(f - 1, c)) / (dt * dt);
        if (acc > r.max_accel) {
          r.max_accel = acc;
          r.max_accel_channel = c;
        }
      }
    }
  }
  return r;
}

}  // namespace kg::synth::test
