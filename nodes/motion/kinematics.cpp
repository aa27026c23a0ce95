#include "kg/motion/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "kg/motion/rotations.hpp"

namespace kg::motion {

namespace {

// Parent frame from joint frame as rotation R and translation t (skeleton.hpp's formula).
inline void local_rt(const Joint& jt, const double* values, Eigen::Matrix3d& R, Eigen::Vector3d& t) {
  t = jt.offset;
  R.setIdentity();
  const double* v = values + jt.first_channel;
  bool rotated = false;
  for (const Channel& ch : jt.channels) {
    const double x = *v++;
    const int axis = static_cast<int>(ch.kind) % 3;
    if (!is_rotation(ch.kind)) {
      t[axis] = x;
    } else {
      post_rotate(R, axis, std::cos(x), std::sin(x));
      rotated = true;
    }
  }
  if (rotated && !is_identity(jt.axis)) R = jt.axis * R * jt.axis.transpose();
}

void check_frame(const Skeleton& skeleton, Eigen::Index frame_size, const char* who) {
  if (frame_size != skeleton.channel_count())
    throw std::invalid_argument(std::string(who) + ": frame has " + std::to_string(frame_size) +
                                " values, skeleton has " + std::to_string(skeleton.channel_count()) +
                                " channels");
}

void check_world(const Skeleton& skeleton, std::size_t world_size, const char* who) {
  if (world_size != static_cast<std::size_t>(skeleton.joint_count()))
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(world_size) +
                                " world transforms for " + std::to_string(skeleton.joint_count()) +
                                " joints");
}

}  // namespace

Eigen::Isometry3d local_transform(const Skeleton& skeleton, int joint, FrameRef frame) {
  check_frame(skeleton, frame.size(), "local_transform");
  if (joint < 0 || joint >= skeleton.joint_count())
    throw std::out_of_range("local_transform: joint " + std::to_string(joint) + " out of range");
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  local_rt(skeleton.joint(joint), frame.data(), R, t);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

void forward_kinematics(const Skeleton& skeleton, FrameRef frame, std::span<Eigen::Isometry3d> world) {
  check_frame(skeleton, frame.size(), "forward_kinematics");
  check_world(skeleton, world.size(), "forward_kinematics");
  const double* values = frame.data();
  const std::vector<Joint>& joints = skeleton.joints();
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const Joint& jt = joints[j];
    local_rt(jt, values, R, t);
    Eigen::Matrix4d& W = world[j].matrix();
    if (jt.parent < 0) {
      W.topLeftCorner<3, 3>().noalias() = skeleton.file_to_world * R;
      W.topRightCorner<3, 1>().noalias() = skeleton.file_to_world * t;
    } else {
      const Eigen::Matrix4d& P = world[static_cast<std::size_t>(jt.parent)].matrix();
      W.topLeftCorner<3, 3>().noalias() = P.topLeftCorner<3, 3>() * R;
      W.topRightCorner<3, 1>().noalias() = P.topLeftCorner<3, 3>() * t + P.topRightCorner<3, 1>();
    }
    W.row(3) << 0, 0, 0, 1;
  }
}

Eigen::MatrixXd joint_world_positions(const Motion& motion) {
  if (!motion.skeleton)
    throw std::invalid_argument("joint_world_positions: motion '" + motion.name + "' has no skeleton");
  const Skeleton& skeleton = *motion.skeleton;
  const int joints = skeleton.joint_count();
  Eigen::MatrixXd out(motion.frame_count(), 3 * joints);
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(joints));
  for (int f = 0; f < motion.frame_count(); ++f) {
    forward_kinematics(skeleton, motion.values.row(f), world);
    for (int j = 0; j < joints; ++j)
      out.block<1, 3>(f, 3 * j) = world[static_cast<std::size_t>(j)].translation().transpose();
  }
  return out;
}

void point_jacobian(const Skeleton& skeleton, FrameRef frame, std::span<const Eigen::Isometry3d> world,
                    int joint, const Eigen::Vector3d& local_point,
                    Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J) {
  check_frame(skeleton, frame.size(), "point_jacobian");
  check_world(skeleton, world.size(), "point_jacobian");
  if (joint < 0 || joint >= skeleton.joint_count())
    throw std::out_of_range("point_jacobian: joint " + std::to_string(joint) + " out of range");
  if (J.cols() != skeleton.channel_count())
    throw std::invalid_argument("point_jacobian: J has " + std::to_string(J.cols()) +
                                " columns, skeleton has " + std::to_string(skeleton.channel_count()) +
                                " channels");
  if (J.outerStride() == 3)
    std::fill_n(J.data(), 3 * J.cols(), 0.0);  // one contiguous block: a plain memset
  else
    J.setZero();
  const double* values = frame.data();
  const Eigen::Vector3d p = world[static_cast<std::size_t>(joint)] * local_point;

  for (int j = joint; j >= 0;) {
    const Joint& jt = skeleton.joint(j);
    const int parent = jt.parent;
    const Eigen::Matrix3d Wp =
        parent >= 0 ? world[static_cast<std::size_t>(parent)].linear() : skeleton.file_to_world;
    const Eigen::Isometry3d& Wj = world[static_cast<std::size_t>(j)];
    const Eigen::Vector3d r = p - Wj.translation();

    // Rotation channel m turns about M_m e_m with M_m = Wp A R_0 ... R_{m-1} (A the joint's axis);
    // Wj A = Wp A R_0 ... R_{n-1} gives the last axis without trigonometry, and at most one
    // rotation (R_0) is needed for the middle one.
    const bool plain = is_identity(jt.axis);
    const Eigen::Matrix3d start = plain ? Wp : Eigen::Matrix3d(Wp * jt.axis);
    int rot_idx[3];
    int n_rot = 0;
    const int n = static_cast<int>(jt.channels.size());
    for (int c = 0; c < n; ++c) {
      const ChannelKind kind = jt.channels[static_cast<std::size_t>(c)].kind;
      const int axis = static_cast<int>(kind) % 3;
      if (is_rotation(kind)) {
        if (n_rot == 3)  // add_joint refuses these; a joint edited through joint_mut may not
          throw std::invalid_argument("point_jacobian: joint '" + jt.name +
                                      "' has more than 3 rotation channels");
        rot_idx[n_rot++] = c;
      } else {
        J.col(jt.first_channel + c) = Wp.col(axis);
      }
    }
    if (n_rot > 0) {
      auto axis_of = [&](int i) {
        return static_cast<int>(jt.channels[static_cast<std::size_t>(rot_idx[i])].kind) % 3;
      };
      J.col(jt.first_channel + rot_idx[0]) = start.col(axis_of(0)).cross(r);
      if (n_rot >= 2) {
        const Eigen::Matrix3d end =
            plain ? Eigen::Matrix3d(Wj.linear()) : Eigen::Matrix3d(Wj.linear() * jt.axis);
        J.col(jt.first_channel + rot_idx[n_rot - 1]) = end.col(axis_of(n_rot - 1)).cross(r);
      }
      if (n_rot == 3) {
        Eigen::Matrix3d mid = start;
        const double x = values[jt.first_channel + rot_idx[0]];
        post_rotate(mid, axis_of(0), std::cos(x), std::sin(x));
        J.col(jt.first_channel + rot_idx[1]) = mid.col(axis_of(1)).cross(r);
      }
    }
    j = parent;
  }
}

std::vector<int> influencing_channels(const Skeleton& skeleton, int joint) {
  if (joint < 0 || joint >= skeleton.joint_count())
    throw std::out_of_range("influencing_channels: joint " + std::to_string(joint) + " out of range");
  std::vector<int> chain;
  for (int j = joint; j >= 0; j = skeleton.joint(j).parent) chain.push_back(j);
  std::vector<int> channels;
  // Ancestors have smaller indices than their descendants (add_joint's order), so walking the
  // chain from the root gives increasing channel indices.
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const Joint& jt = skeleton.joint(*it);
    for (int c = 0; c < static_cast<int>(jt.channels.size()); ++c) channels.push_back(jt.first_channel + c);
  }
  return channels;
}

}  // namespace kg::motion
