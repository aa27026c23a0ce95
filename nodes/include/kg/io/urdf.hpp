// Robots from URDF files (read with urdfdom): the kinematic tree as a motion::Skeleton, and what
// a retargeting or a retiming needs besides (degrees of freedom with their limits, link inertias).
//
//   Robot g1 = read_urdf("g1_29dof.urdf");
//   int foot = g1.find_link("left_ankle_roll_link")->joint;   // its skeleton joint
//   const RobotDof& knee = g1.dofs[g1.find_dof("left_knee_joint")];
//
// The skeleton (skeleton.hpp's conventions) has the root link, then one joint per URDF joint
// (fixed ones too), named after it, in the file's order except that a joint listed before its
// parent's is placed after it ("the robot's order": the file's own when parents come first). A
// link is found through Robot::links. Each joint's frame is the link's frame turned so that it is aligned
// with the URDF's base frame when every joint is at zero (so skeleton offsets are the links' rest positions
// in base coordinates, and the URDF's origin rpy are folded into the offsets and axes); forward kinematics
// then gives every link's origin exactly where the URDF puts it, and its orientation as the URDF's times the
// link's constant rest rotation (RobotLink::rest_rotation). The root (the URDF's root link) is a floating
// base: Xposition Yposition Zposition Zrotation Yrotation Xrotation. A revolute or continuous joint is one
// Xrotation channel about its axis (Joint::axis' first column is the axis, in the parent's rest-aligned
// frame); a prismatic joint along an axis of the base frame is one position channel whose value is the rest
// offset plus (or minus) the joint's position; a fixed joint has no channel. Units: metres, radians,
// kilograms; the URDF is Z up (REP 103), so skeleton->file_to_world turns Z up to the skeleton convention's Y
// up.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "kg/io/import_options.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::io {

enum class RobotJointType { Revolute, Continuous, Prismatic };
const char* to_string(RobotJointType type);

// One actuated joint of the URDF (fixed joints are not degrees of freedom).
struct RobotDof {
  std::string name;  // the URDF joint's name
  RobotJointType type = RobotJointType::Revolute;
  int joint = -1;    // the skeleton joint it moves (its child link)
  int channel = -1;  // that joint's channel in a frame's values
  // Position = sign * (channel value - offset): 1 and 0 for rotations; for a prismatic joint the
  // rest offset component its channel replaces and the direction of its axis along it.
  double sign = 1, offset = 0;
  double lower = 0, upper = 0;  // radians or metres; -inf, +inf for continuous joints
  double velocity = 0;          // rad/s or m/s; 0 when the file states none
  double effort = 0;            // N·m or N; 0 when the file states none
  int line = 0;                 // of its <joint> element in the file
};

struct RobotLink {
  std::string name;
  int joint = -1;  // its skeleton joint
  // Its <inertial>: kilograms; centre of mass and inertia about it in the skeleton joint's frame.
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  // The URDF link frame's rotation in base coordinates with every joint at zero: the URDF's
  // orientation of the link is the skeleton joint's times rest_rotation.
  Eigen::Matrix3d rest_rotation = Eigen::Matrix3d::Identity();
  int line = 0;  // of its <link> element
};

struct Robot {
  std::string name;  // <robot name>
  std::string path;  // the file read
  std::shared_ptr<const motion::Skeleton> skeleton;
  std::vector<RobotDof> dofs;    // the actuated joints in the robot's order (skeleton order)
  std::vector<RobotLink> links;  // in skeleton joint order: links[i].joint == i
  double total_mass() const;
  // The dof named `name` (a URDF joint), -1 when absent.
  int find_dof(const std::string& name) const;
  // The link named `name`, null when absent.
  const RobotLink* find_link(const std::string& name) const;
};

// Reads a URDF file. Throws kg::Error naming the file and, where it can, the line of the
// element at fault (urdfdom's own message kept): not XML, not a <robot>, a joint whose parent or
// child link is missing, a link with two parents or a loop (no root), a joint type it cannot
// move (floating and planar joints below the root), a prismatic joint not along an axis of the
// base frame, limits that are not finite or reversed.
Robot read_urdf(const std::string& path);
// The same from the file's text; `path` names it in messages.
Robot parse_urdf(const std::string& text, const std::string& path);

// The URDF as a clip: one frame, every joint at zero, the base at the origin, at 30 frames per
// second, for inspect, convert (a BVH of the robot's tree) and as a retargeting target.
// options.units: auto or m (metres, as URDF states; another unit scales the file); options.up:
// auto or z (REP 103), or y for a file that breaks it; trim and fps are ignored. Said in notes.
ImportedMotion import_urdf(const std::string& path, const ImportOptions& options);

}  // namespace kg::io
