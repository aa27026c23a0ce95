// Forward kinematics and analytic Jacobians of points fixed on segments (skeleton.hpp's
// conventions: metres, radians, world +Y up). Caller-owned buffers, no allocation per call
// (ozz-animation's job style), so the hot loops of solvers and importers stay allocation-free.
//
//   std::vector<Eigen::Isometry3d> world(skeleton.joint_count());
//   forward_kinematics(skeleton, motion.values.row(f), world);       // world from joint frame
//   Eigen::Vector3d p = world[foot] * toe_local;                     // a point fixed on a segment
//   Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, skeleton.channel_count());
//   point_jacobian(skeleton, motion.values.row(f), world, foot, toe_local, J);
#pragma once

#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "kg/motion/motion.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::motion {

using FrameRef = Eigen::Ref<const Eigen::RowVectorXd>;

// Local transform of one joint (parent frame from joint frame) for one frame's values
// (skeleton.channel_count() values).
Eigen::Isometry3d local_transform(const Skeleton& skeleton, int joint, FrameRef frame);

// world[j] = world from joint j's frame, file_to_world included. world.size() == joint_count().
void forward_kinematics(const Skeleton& skeleton, FrameRef frame, std::span<Eigen::Isometry3d> world);

// World positions (metres) of every joint origin for every frame: frames x (3 * joints),
// row f = [x0 y0 z0 x1 y1 z1 ...].
Eigen::MatrixXd joint_world_positions(const Motion& motion);

// d(world position of `local_point` fixed in `joint`'s frame) / d(frame value) for every channel:
// J is 3 x channel_count(); columns of channels that do not move the point are set to zero.
// `world` must be forward_kinematics of the same frame.
void point_jacobian(const Skeleton& skeleton, FrameRef frame, std::span<const Eigen::Isometry3d> world,
                    int joint, const Eigen::Vector3d& local_point,
                    Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J);

// The channels that can move a point on `joint`: those of the joint and its ancestors, in
// increasing channel index. point_jacobian's non-zero columns are a subset of these.
std::vector<int> influencing_channels(const Skeleton& skeleton, int joint);

}  // namespace kg::motion
