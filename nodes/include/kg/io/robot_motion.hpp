// A robot's motion as robot-learning pipelines read it (the fields of GMR's files): a floating
// base and one value per degree of freedom, per frame.
//
//   RobotTrajectory t = robot_trajectory(walk_on_g1);  // a motion on read_urdf's skeleton
//   write_robot_csv(os, t);    // time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw,<dofs>
//
// A robot motion is one whose root has three position and three rotation channels and whose
// other joints have at most one channel each (urdf.hpp's skeletons; any skeleton so built). The
// degrees of freedom are those joints with a channel, in skeleton order (a URDF's file order when
// it lists parents first); a rotation channel's value is the joint's angle, a position channel's
// is sign * (value - rest offset), the sign being that of its joint's axis along the channel
// (urdf.hpp). The base is written in Z-up coordinates (REP 103): metres; its rotation as a unit
// quaternion x, y, z, w, the sign kept continuous from frame to frame (w >= 0 on the first).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"

namespace kg::io {

struct RobotTrajectory {
  double fps = 30;
  std::vector<std::string> joint_names;  // the degrees of freedom
  Eigen::MatrixXd root_pos;              // frames x 3, metres, Z up
  Eigen::MatrixXd root_rot;              // frames x 4, x y z w
  Eigen::MatrixXd dof_pos;               // frames x joint_names.size(), radians or metres
};

// Throws std::invalid_argument naming the first joint that breaks the shape above, or for a
// motion failing check().
RobotTrajectory robot_trajectory(const motion::Motion& motion);

// A header row, then one row per frame: time (seconds from 0), root_x, root_y, root_z, root_qx,
// root_qy, root_qz, root_qw, then each degree of freedom; `precision` digits after the point.
void write_robot_csv(std::ostream& os, const RobotTrajectory& trajectory, int precision = 6);
// {"fps": f, "joint_names": [...], "root_pos": [[x,y,z],...], "root_rot": [[x,y,z,w],...],
//  "dof_pos": [[...],...]}.
void write_robot_json(std::ostream& os, const RobotTrajectory& trajectory);

// Reads write_robot_csv's text back onto `robot`'s skeleton (read_urdf, urdf.hpp): columns by
// name in any order after the eight base columns (every degree of freedom of the robot once; no
// other column), the base quaternion normalised, the frame rate from the time column (which must
// rise by one constant step, within a hundredth of it; an integer or NTSC rate when the printed
// times fix it to 1e-4, so 30, not 30.0001) unless `fps` > 0 overrides it; the first row is
// frame 0, whatever its time. `path` names the file
// in messages. Throws kg::Error at file:line for a missing or unknown column (with the nearest
// joint name), a row of the wrong length, a value that is not a finite number, a zero
// quaternion, or times that are not evenly spaced.
struct Robot;
motion::Motion parse_robot_csv(const std::string& text, const std::string& path, const Robot& robot,
                               double fps = 0);

}  // namespace kg::io
