// Robot motions as CSV and JSON (robot_motion.hpp).
#include "kg/io/robot_motion.hpp"

#include <cstdio>
#include <stdexcept>

#include "kg/base/json.hpp"
#include "kg/base/text.hpp"
#include "kg/io/import_options.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::io {

namespace {

void require_robot_shape(const motion::Motion& motion) {
  const motion::Skeleton& s = *motion.skeleton;
  const std::string who = motion.name.empty() ? std::string("the motion") : text::excerpt(motion.name);
  if (s.joint_count() == 0) throw std::invalid_argument(who + " has no joints: not a robot motion");
  const motion::Joint& root = s.joint(0);
  int positions = 0, rotations = 0;
  for (const motion::Channel& c : root.channels) (motion::is_rotation(c.kind) ? rotations : positions) += 1;
  if (positions != 3 || rotations != 3)
    throw std::invalid_argument(who + ": a robot motion's root " + text::excerpt(root.name) +
                                " has 3 position and 3 rotation channels (a floating base); it has " +
                                std::to_string(positions) + " and " + std::to_string(rotations));
  for (int j = 1; j < s.joint_count(); ++j) {
    if (s.joint(j).parent < 0)
      throw std::invalid_argument(who + ": a robot motion has one root; " + text::excerpt(s.joint(j).name) +
                                  " is a second");
    if (s.joint(j).channels.size() > 1)
      throw std::invalid_argument(who +
                                  ": a robot motion has at most one channel per joint (a URDF target's "
                                  "skeleton); joint " +
                                  text::excerpt(s.joint(j).name) + " has " +
                                  std::to_string(s.joint(j).channels.size()));
  }
}

}  // namespace

RobotTrajectory robot_trajectory(const motion::Motion& motion) {
  motion.check();
  require_robot_shape(motion);
  const motion::Skeleton& s = *motion.skeleton;
  RobotTrajectory out;
  out.fps = motion.fps;
  std::vector<int> joints;
  for (int j = 1; j < s.joint_count(); ++j)
    if (!s.joint(j).channels.empty()) {
      joints.push_back(j);
      out.joint_names.push_back(s.joint(j).name);
    }
  const int frames = motion.frame_count();
  out.root_pos.resize(frames, 3);
  out.root_rot.resize(frames, 4);
  out.dof_pos.resize(frames, static_cast<Eigen::Index>(joints.size()));
  const Eigen::Matrix3d to_z_up = z_up_to_y_up().transpose() * s.file_to_world;
  Eigen::Quaterniond previous(1, 0, 0, 0);
  for (int f = 0; f < frames; ++f) {
    const auto row = motion.values.row(f);
    const Eigen::Isometry3d base = motion::local_transform(s, 0, row);
    out.root_pos.row(f) = (to_z_up * base.translation()).transpose();
    Eigen::Quaterniond q(to_z_up * base.linear());
    q.normalize();
    if ((f == 0 && q.w() < 0) || (f > 0 && q.dot(previous) < 0)) q.coeffs() = -q.coeffs();
    previous = q;
    out.root_rot.row(f) << q.x(), q.y(), q.z(), q.w();
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const motion::Joint& j = s.joint(joints[i]);
      const double v = row[j.first_channel];
      double value = v;
      if (!motion::is_rotation(j.channels[0].kind)) {
        const int k = motion::axis_index(j.channels[0].kind);
        value = (j.axis(k, 0) < 0 ? -1.0 : 1.0) * (v - j.offset[k]);
      }
      out.dof_pos(f, static_cast<Eigen::Index>(i)) = value + 0.0;  // no -0 written
    }
  }
  return out;
}

void write_robot_csv(std::ostream& os, const RobotTrajectory& t, int precision) {
  os << "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw";
  for (const std::string& name : t.joint_names) os << ',' << name;
  os << '\n';
  char buf[64];
  auto put = [&](double x) {
    std::snprintf(buf, sizeof buf, "%.*f", precision, x);
    os << ',' << buf;
  };
  for (Eigen::Index f = 0; f < t.root_pos.rows(); ++f) {
    std::snprintf(buf, sizeof buf, "%.*f", precision, static_cast<double>(f) / t.fps);
    os << buf;
    for (int k = 0; k < 3; ++k) put(t.root_pos(f, k));
    for (int k = 0; k < 4; ++k) put(t.root_rot(f, k));
    for (Eigen::Index k = 0; k < t.dof_pos.cols(); ++k) put(t.dof_pos(f, k));
    os << '\n';
  }
}

void write_robot_json(std::ostream& os, const RobotTrajectory& t) {
  JsonWriter w(os, 0);
  auto rows = [&](const Eigen::MatrixXd& m) {
    w.begin_array();
    for (Eigen::Index f = 0; f < m.rows(); ++f) {
      w.begin_array();
      for (Eigen::Index k = 0; k < m.cols(); ++k) w.value(m(f, k));
      w.end_array();
    }
    w.end_array();
  };
  w.begin_object();
  w.key("fps");
  w.value(t.fps);
  w.key("joint_names");
  w.begin_array();
  for (const std::string& n : t.joint_names) w.value(n);
  w.end_array();
  w.key("root_pos");
  rows(t.root_pos);
  w.key("root_rot");
  rows(t.root_rot);
  w.key("dof_pos");
  rows(t.dof_pos);
  w.end_object();
  os << '\n';
}

}  // namespace kg::io
