// Euler angles in any order of rotation channels, to and from rotation matrices and quaternions.
// Convention (skeleton.hpp, BVH): the first listed rotation is the outermost,
//   R = R(a0) * R(a1) * R(a2),   column vectors, right-handed, radians.
// An order holds 0..3 axes; neighbouring axes differ (XYZ, ZXY, ZXZ, XY, Y, "" are orders; XXY
// is not). Converting back picks, of the angle sets giving the matrix, the one nearest a
// reference (usually the previous frame), so curves stay continuous across +-180 degrees and
// through gimbal lock.
//
//   RotationOrder zxy = parse_rotation_order("ZXY");
//   Eigen::Matrix3d R = euler_to_matrix(zxy, Eigen::Vector3d(0.1, 0.2, 0.3));
//   Eigen::Vector3d back = matrix_to_euler(R, zxy, previous_angles);   // ~ (0.1, 0.2, 0.3)
#pragma once

#include <array>
#include <string>
#include <string_view>

#include <Eigen/Geometry>

#include "kg/motion/skeleton.hpp"

namespace kg::motion {

// The rotation axes of a joint in listed order: axes[0..count) in {0, 1, 2} for X, Y, Z.
struct RotationOrder {
  std::array<int, 3> axes{0, 0, 0};
  int count = 0;

  bool operator==(const RotationOrder&) const = default;
};

// "ZXY" (case-insensitive, 0 to 3 letters). Throws std::invalid_argument naming the text for other
// letters, more than 3 axes or two equal neighbouring axes.
RotationOrder parse_rotation_order(std::string_view text);
// "ZXY"; "" for no axes.
std::string to_string(const RotationOrder& order);

// The joint's rotation channels in listed order. Throws std::invalid_argument for an invalid
// order (Skeleton::add_joint refuses those, so never for a joint of a Skeleton).
RotationOrder rotation_order(const Joint& joint);
// Where each of those rotation channels sits in joint.channels: indices[i] for axes[i].
std::array<int, 3> rotation_channel_indices(const Joint& joint);

// Wraps to (-pi, pi].
double wrap_angle(double angle);
// angle + 2 pi k for the integer k bringing it nearest `reference`.
double nearest_angle(double angle, double reference);

// Rotation by `angle` radians about axis 0, 1 or 2.
Eigen::Matrix3d axis_rotation(int axis, double angle);

// angles[i] about order.axes[i], i < order.count; the remaining entries are ignored.
Eigen::Matrix3d euler_to_matrix(const RotationOrder& order, const Eigen::Vector3d& angles);
Eigen::Quaterniond euler_to_quaternion(const RotationOrder& order, const Eigen::Vector3d& angles);

// Angles (entries past order.count are 0) of `R` in `order`, nearest `reference` (radians, same
// layout): among the exact solutions (two for three distinct axes, two for ZXZ-like orders, each
// up to 2 pi per angle) the one of least squared distance; in gimbal lock, where only a sum or
// difference of the outer angles is determined, it is split so both stay nearest the reference.
// With fewer than 3 axes a rotation outside their span is projected: 1 axis gives the twist about
// it; 2 axes (R ~ R_i(a) R_j(b)) take a from R's image of axis j and b as the remaining twist
// about j. `R` must be a rotation matrix.
Eigen::Vector3d matrix_to_euler(const Eigen::Matrix3d& R, const RotationOrder& order,
                                const Eigen::Vector3d& reference = Eigen::Vector3d::Zero());
Eigen::Vector3d quaternion_to_euler(const Eigen::Quaterniond& q, const RotationOrder& order,
                                    const Eigen::Vector3d& reference = Eigen::Vector3d::Zero());

// The rotation a joint's channels make in `frame` (skeleton.channel_count() values), its axis
// included: axis * R(c0) R(c1) R(c2) * axis^T, the rotation part of its local transform.
Eigen::Matrix3d joint_rotation(const Skeleton& skeleton, int joint,
                               const Eigen::Ref<const Eigen::RowVectorXd>& frame);
// Writes the joint's rotation channels in `frame` so that joint_rotation gives R (projected as
// matrix_to_euler says when the joint has fewer than 3 rotation channels), the angles nearest
// the values `frame` held before. Other channels are untouched.
void set_joint_rotation(const Skeleton& skeleton, int joint, const Eigen::Matrix3d& R,
                        Eigen::Ref<Eigen::RowVectorXd> frame);

// M <- M * axis_rotation(axis, angle) given c = cos(angle), s = sin(angle), touching only the two
// columns the rotation mixes (the hot loops of forward kinematics and dynamics).
inline void post_rotate(Eigen::Matrix3d& M, int axis, double c, double s) {
  const int l = axis == 2 ? 0 : axis + 1;
  const int m = axis == 0 ? 2 : axis - 1;
  const Eigen::Vector3d cl = M.col(l);
  const Eigen::Vector3d cm = M.col(m);
  M.col(l) = c * cl + s * cm;
  M.col(m) = c * cm - s * cl;
}

// Exactly the identity (an ASF axis frame left at 0 0 0 skips its two products).
inline bool is_identity(const Eigen::Matrix3d& A) {
  return A(0, 0) == 1 && A(1, 1) == 1 && A(2, 2) == 1 && A(0, 1) == 0 && A(0, 2) == 0 && A(1, 0) == 0 &&
         A(1, 2) == 0 && A(2, 0) == 0 && A(2, 1) == 0;
}

// Spherical interpolation a -> b at u in [0, 1] along the shorter arc (b's sign flipped when the
// two lie in opposite hemispheres). Unit quaternions in, unit quaternion out.
Eigen::Quaterniond slerp_shortest(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double u);

}  // namespace kg::motion
