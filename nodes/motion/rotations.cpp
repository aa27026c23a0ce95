#include "kg/motion/rotations.hpp"

#include <cctype>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace kg::motion {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Below this |cos b| (three distinct axes) or |sin b| (repeated axis) the outer angles are no
// longer separable from the matrix to useful precision: treat as gimbal lock.
constexpr double kGimbalEps = 1e-9;

// +1 when (i, j, k) is a cyclic permutation of (0, 1, 2), -1 otherwise.
int parity(int i, int j) {
  return (j - i + 3) % 3 == 1 ? 1 : -1;
}
int third_axis(int i, int j) {
  return 3 - i - j;
}

// Angle of the rotation about `axis` nearest (least squares) to M.
double twist_angle(const Eigen::Matrix3d& M, int axis) {
  const int l = (axis + 1) % 3, m = (axis + 2) % 3;
  return std::atan2(M(m, l) - M(l, m), M(l, l) + M(m, m));
}

double squared_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& ref, int n) {
  double d = 0;
  for (int i = 0; i < n; ++i) d += (a[i] - ref[i]) * (a[i] - ref[i]);
  return d;
}

Eigen::Vector3d shifted_towards(Eigen::Vector3d a, const Eigen::Vector3d& ref, int n) {
  for (int i = 0; i < n; ++i) a[i] = nearest_angle(a[i], ref[i]);
  return a;
}

// R = R_i(a) R_j(b) R_o(c), o == i for ZXZ-like orders, the third axis otherwise.
Eigen::Vector3d three_axis_to_euler(const Eigen::Matrix3d& R, int i, int j, int o,
                                    const Eigen::Vector3d& ref) {
  const int k = third_axis(i, j);
  const int s = parity(i, j);
  const bool repeated = (o == i);
  double a, b, c;
  double sigma;  // in gimbal lock R = R_i(a + sigma * c) R_j(b)
  bool locked;
  if (!repeated) {
    const double cb = std::hypot(R(i, i), R(i, j));
    b = std::atan2(s * R(i, k), cb);
    locked = cb < kGimbalEps;
    a = std::atan2(-s * R(j, k), R(k, k));
    c = std::atan2(-s * R(i, j), R(i, i));
    sigma = s * (b > 0 ? 1.0 : -1.0);
  } else {
    const double sb = std::hypot(R(j, i), R(k, i));
    b = std::atan2(sb, R(i, i));
    locked = sb < kGimbalEps;
    a = std::atan2(R(j, i), -s * R(k, i));
    c = std::atan2(R(i, j), s * R(i, k));
    sigma = R(i, i) > 0 ? 1.0 : -1.0;
  }

  if (locked) {
    b = nearest_angle(b, ref[1]);
    // Only theta = a + sigma c is determined: split its distance from the reference's evenly.
    const double theta = twist_angle(R * axis_rotation(j, b).transpose(), i);
    const double d = wrap_angle(theta - (ref[0] + sigma * ref[2]));
    return {ref[0] + 0.5 * d, b, ref[2] + sigma * 0.5 * d};
  }

  const Eigen::Vector3d first = shifted_towards({a, b, c}, ref, 3);
  const Eigen::Vector3d second = shifted_towards({a + kPi, repeated ? -b : kPi - b, c + kPi}, ref, 3);
  return squared_distance(first, ref, 3) <= squared_distance(second, ref, 3) ? first : second;
}

// R ~ R_i(a) R_j(b), i != j: R's column j is R_i(a) e_j, which fixes a; b is then the twist about j
// of what remains.
Eigen::Vector3d two_axis_to_euler(const Eigen::Matrix3d& R, int i, int j, const Eigen::Vector3d& ref) {
  const int k = third_axis(i, j);
  const int s = parity(i, j);
  const double y = s * R(k, j), x = R(j, j);
  const double a = std::hypot(x, y) < kGimbalEps ? ref[0] : std::atan2(y, x);
  const double b = twist_angle(axis_rotation(i, a).transpose() * R, j);
  return {nearest_angle(a, ref[0]), nearest_angle(b, ref[1]), 0.0};
}

}  // namespace

RotationOrder parse_rotation_order(std::string_view text) {
  RotationOrder order;
  if (text.size() > 3)
    throw std::invalid_argument("rotation order '" + std::string(text) + "': at most 3 axes");
  for (char ch : text) {
    const char up = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    if (up < 'X' || up > 'Z')
      throw std::invalid_argument("rotation order '" + std::string(text) + "': expected letters X, Y, Z");
    const int axis = up - 'X';
    if (order.count > 0 && order.axes[static_cast<std::size_t>(order.count - 1)] == axis)
      throw std::invalid_argument("rotation order '" + std::string(text) +
                                  "': two neighbouring rotations about the same axis");
    order.axes[static_cast<std::size_t>(order.count++)] = axis;
  }
  return order;
}

std::string to_string(const RotationOrder& order) {
  std::string s;
  for (int i = 0; i < order.count; ++i) s += static_cast<char>('X' + order.axes[static_cast<std::size_t>(i)]);
  return s;
}

RotationOrder rotation_order(const Joint& joint) {
  std::string letters;
  for (const Channel& c : joint.channels)
    if (is_rotation(c.kind)) letters += static_cast<char>('X' + axis_index(c.kind));
  try {
    return parse_rotation_order(letters);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("joint '" + joint.name + "': " + e.what());
  }
}

std::array<int, 3> rotation_channel_indices(const Joint& joint) {
  std::array<int, 3> idx{-1, -1, -1};
  std::size_t n = 0;
  for (std::size_t c = 0; c < joint.channels.size(); ++c) {
    if (!is_rotation(joint.channels[c].kind)) continue;
    if (n == 3) throw std::invalid_argument("joint '" + joint.name + "': more than 3 rotation channels");
    idx[n++] = static_cast<int>(c);
  }
  return idx;
}

double wrap_angle(double angle) {
  double r = std::remainder(angle, kTwoPi);  // [-pi, pi]
  if (r <= -kPi) r += kTwoPi;
  return r;
}

double nearest_angle(double angle, double reference) {
  // Whole turns added explicitly so an angle already nearest comes back bit for bit.
  const double turns = std::round((reference - angle) / kTwoPi);
  return turns == 0 ? angle : angle + turns * kTwoPi;
}

Eigen::Matrix3d axis_rotation(int axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  const int l = (axis + 1) % 3, m = (axis + 2) % 3;
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  R(axis, axis) = 1;
  R(l, l) = c;
  R(m, m) = c;
  R(m, l) = s;
  R(l, m) = -s;
  return R;
}

Eigen::Matrix3d euler_to_matrix(const RotationOrder& order, const Eigen::Vector3d& angles) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int i = 0; i < order.count; ++i)
    R = R * axis_rotation(order.axes[static_cast<std::size_t>(i)], angles[i]);
  return R;
}

Eigen::Quaterniond euler_to_quaternion(const RotationOrder& order, const Eigen::Vector3d& angles) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (int i = 0; i < order.count; ++i) {
    const double h = 0.5 * angles[i];
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    v[order.axes[static_cast<std::size_t>(i)]] = std::sin(h);
    q = q * Eigen::Quaterniond(std::cos(h), v.x(), v.y(), v.z());
  }
  return q;
}

Eigen::Vector3d matrix_to_euler(const Eigen::Matrix3d& R, const RotationOrder& order,
                                const Eigen::Vector3d& reference) {
  const auto& ax = order.axes;
  for (int i = 0; i < order.count && i < 3; ++i) {
    const int a = ax[static_cast<std::size_t>(i)];
    if (a < 0 || a > 2 || (i > 0 && a == ax[static_cast<std::size_t>(i - 1)]))
      throw std::invalid_argument("invalid rotation order '" + to_string(order) + "'");
  }
  switch (order.count) {
    case 0:
      return Eigen::Vector3d::Zero();
    case 1:
      return {nearest_angle(twist_angle(R, ax[0]), reference[0]), 0.0, 0.0};
    case 2:
      return two_axis_to_euler(R, ax[0], ax[1], reference);
    case 3:
      return three_axis_to_euler(R, ax[0], ax[1], ax[2], reference);
    default:
      throw std::invalid_argument("rotation order with " + std::to_string(order.count) + " axes");
  }
}

Eigen::Vector3d quaternion_to_euler(const Eigen::Quaterniond& q, const RotationOrder& order,
                                    const Eigen::Vector3d& reference) {
  return matrix_to_euler(q.normalized().toRotationMatrix(), order, reference);
}

namespace {

void check_joint_frame(const Skeleton& skeleton, int joint, Eigen::Index frame_size, const char* who) {
  if (joint < 0 || joint >= skeleton.joint_count())
    throw std::out_of_range(std::string(who) + ": joint " + std::to_string(joint) + " out of range");
  if (frame_size != skeleton.channel_count())
    throw std::invalid_argument(std::string(who) + ": frame has " + std::to_string(frame_size) +
                                " values, skeleton has " + std::to_string(skeleton.channel_count()) +
                                " channels");
}

}  // namespace

Eigen::Matrix3d joint_rotation(const Skeleton& skeleton, int joint,
                               const Eigen::Ref<const Eigen::RowVectorXd>& frame) {
  check_joint_frame(skeleton, joint, frame.size(), "joint_rotation");
  const Joint& jt = skeleton.joint(joint);
  const RotationOrder order = rotation_order(jt);
  const std::array<int, 3> idx = rotation_channel_indices(jt);
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  for (int r = 0; r < order.count; ++r) a[r] = frame[jt.first_channel + idx[static_cast<std::size_t>(r)]];
  return jt.axis * euler_to_matrix(order, a) * jt.axis.transpose();
}

void set_joint_rotation(const Skeleton& skeleton, int joint, const Eigen::Matrix3d& R,
                        Eigen::Ref<Eigen::RowVectorXd> frame) {
  check_joint_frame(skeleton, joint, frame.size(), "set_joint_rotation");
  const Joint& jt = skeleton.joint(joint);
  const RotationOrder order = rotation_order(jt);
  const std::array<int, 3> idx = rotation_channel_indices(jt);
  Eigen::Vector3d ref = Eigen::Vector3d::Zero();
  for (int r = 0; r < order.count; ++r) ref[r] = frame[jt.first_channel + idx[static_cast<std::size_t>(r)]];
  const Eigen::Vector3d a = matrix_to_euler(jt.axis.transpose() * R * jt.axis, order, ref);
  for (int r = 0; r < order.count; ++r) frame[jt.first_channel + idx[static_cast<std::size_t>(r)]] = a[r];
}

Eigen::Quaterniond slerp_shortest(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double u) {
  const Eigen::Quaterniond bb = a.dot(b) < 0 ? Eigen::Quaterniond(-b.coeffs()) : b;
  return a.slerp(u, bb).normalized();
}

}  // namespace kg::motion
