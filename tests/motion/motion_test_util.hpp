// Skeletons and poses shared by the motion tests.
#pragma once

#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "kg/motion/motion.hpp"
#include "kg/motion/rotations.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::motion::test {

inline constexpr double kPi = std::numbers::pi;

inline std::vector<Channel> channels_of(const std::vector<ChannelKind>& kinds) {
  std::vector<Channel> out;
  for (ChannelKind k : kinds) out.push_back({k});
  return out;
}

inline std::vector<ChannelKind> rotations_in(const std::string& order) {
  std::vector<ChannelKind> out;
  for (char c : order) out.push_back(static_cast<ChannelKind>(3 + (c - 'X')));
  return out;
}

// A branching skeleton of 14 joints exercising every convention: a Z-up file, mixed rotation
// orders (Tait-Bryan, repeated-axis, 1 and 2 axes, none), position channels on non-root joints
// interleaved with rotations, ASF-style axes and end sites.
inline std::shared_ptr<const Skeleton> mixed_skeleton() {
  using K = ChannelKind;
  auto s = std::make_shared<Skeleton>();
  s->file_to_world = axis_rotation(0, -kPi / 2);  // file +Z up -> world +Y up
  auto add = [&](const std::string& name, int parent, Eigen::Vector3d offset, std::vector<ChannelKind> kinds,
                 Eigen::Matrix3d axis = Eigen::Matrix3d::Identity()) {
    Joint j;
    j.name = name;
    j.parent = parent;
    j.offset = offset;
    j.axis = axis;
    j.channels = channels_of(kinds);
    return s->add_joint(std::move(j));
  };
  const int root = add("root", -1, {0.1, -0.2, 0.9},
                       {K::Xposition, K::Yposition, K::Zposition, K::Zrotation, K::Yrotation, K::Xrotation});
  const int spine = add("spine", root, {0, 0, 0.12}, {K::Zrotation, K::Xrotation, K::Yrotation});
  const int chest = add("chest", spine, {0.01, 0.02, 0.2},
                        {K::Xposition, K::Yrotation, K::Zposition, K::Xrotation, K::Zrotation},
                        euler_to_matrix(parse_rotation_order("XYZ"), {0.3, -0.2, 0.5}));
  const int neck = add("neck", chest, {0, 0.03, 0.18}, rotations_in("ZXZ"));
  const int head = add("head", neck, {0, 0.01, 0.1}, {});
  s->joint_mut(head).end_sites.push_back({0, 0, 0.15});
  const int lsh = add("lshoulder", chest, {0.18, 0, 0.1}, rotations_in("YX"),
                      euler_to_matrix(parse_rotation_order("ZYX"), {0.9, 0.1, -0.4}));
  const int lelb = add("lelbow", lsh, {0.28, 0, 0}, rotations_in("Y"));
  const int lhand = add("lhand", lelb, {0.25, 0.01, 0},
                        {K::Xrotation, K::Xposition, K::Yposition, K::Zposition, K::Yrotation, K::Zrotation});
  s->joint_mut(lhand).end_sites.push_back({0.08, 0, 0});
  const int rsh = add("rshoulder", chest, {-0.18, 0, 0.1}, rotations_in("XZX"));
  add("relbow", rsh, {-0.28, 0, 0}, {K::Zposition, K::Xrotation});
  const int lhip = add("lhip", root, {0.09, 0, -0.05}, rotations_in("YZX"));
  const int lknee = add("lknee", lhip, {0, 0.01, -0.42}, rotations_in("X"),
                        euler_to_matrix(parse_rotation_order("Z"), Eigen::Vector3d(0.35, 0, 0)));
  add("lfoot", lknee, {0, -0.02, -0.41}, rotations_in("XZ"));
  add("rhip", root, {-0.09, 0, -0.05}, {K::Yposition, K::Xrotation, K::Yrotation, K::Zrotation});
  return s;
}

// A frame of plausible values: position channels near the offsets they replace, angles anywhere.
inline Eigen::RowVectorXd random_frame(const Skeleton& s, std::mt19937& rng, double angle_range = kPi) {
  std::uniform_real_distribution<double> angle(-angle_range, angle_range), jitter(-0.05, 0.05);
  Eigen::RowVectorXd f(s.channel_count());
  for (const Joint& j : s.joints())
    for (std::size_t c = 0; c < j.channels.size(); ++c) {
      const ChannelKind k = j.channels[c].kind;
      f[j.first_channel + static_cast<int>(c)] =
          is_rotation(k) ? angle(rng) : j.offset[axis_index(k)] + jitter(rng);
    }
  return f;
}

}  // namespace kg::motion::test
