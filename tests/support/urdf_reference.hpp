// Test support: a URDF's forward kinematics as its specification defines it, from urdfdom's own
// parse, independent of kg::io's conversion to a Skeleton (tests link urdfdom for it).
//
//   auto poses = kg::test::urdf_link_poses(*urdf::parseURDFFile(path), {{"knee", 0.5}}, base);
#pragma once

#include <map>
#include <string>
#include <vector>

#include <urdf_parser/urdf_parser.h>
#include <Eigen/Geometry>

namespace kg::test {

inline Eigen::Isometry3d pose_of(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

// Every link's transform in the URDF's base coordinates: parent * origin * motion(q) down the
// tree, as the URDF specification defines it; `q` by joint name, `base` the root's pose.
inline std::map<std::string, Eigen::Isometry3d> urdf_link_poses(const urdf::ModelInterface& model,
                                                                const std::map<std::string, double>& q,
                                                                const Eigen::Isometry3d& base) {
  std::map<std::string, Eigen::Isometry3d> out;
  std::vector<urdf::LinkConstSharedPtr> stack{model.getRoot()};
  out[model.getRoot()->name] = base;
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr link = stack.back();
    stack.pop_back();
    for (const urdf::JointSharedPtr& joint : link->child_joints) {
      Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
      const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
      const double value = q.count(joint->name) ? q.at(joint->name) : 0.0;
      if (joint->type == urdf::Joint::PRISMATIC) m.translation() = value * axis.normalized();
      if (joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS)
        m.linear() = Eigen::AngleAxisd(value, axis.normalized()).toRotationMatrix();
      out[joint->child_link_name] = out[link->name] * pose_of(joint->parent_to_joint_origin_transform) * m;
      stack.push_back(model.getLink(joint->child_link_name));
    }
  }
  return out;
}

}  // namespace kg::test
