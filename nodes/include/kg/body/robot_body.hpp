// A robot's own body (McCann et al. 2006 §3.1 with the robot's data instead of a segment table):
// the link masses, centres of mass and inertias of its URDF, its joints' effort limits as torque
// limits, for retiming a motion on that robot under its own dynamics.
//
//   Robot g1 = io::read_urdf("g1_29dof.urdf");
//   RobotBody b = robot_body_model(g1, walk.skeleton);   // walk: a motion on the G1
//
// The motion's skeleton must be the robot's tree: the same joints by name, in the same order,
// at the same rest offsets (within 1e-6 m): read_urdf's skeleton, or a BVH of it written and
// read back (whose joint frames are the same, rest-aligned ones). Each joint's segment is its
// child link's inertial, in that frame. Torque limits: a joint with the robot's one channel gets
// +-effort on it (unlimited where the URDF states no effort); a joint with more channels (a BVH
// of the robot's tree, three rotations per joint) is unlimited, since its channels' axes are not
// the actuated one, and a note says so; the root is unactuated (0, 0). Gravity is world -Y
// (skeleton.hpp: the URDF's -Z), `gravity` m/s² long.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "kg/body/body_model.hpp"
#include "kg/io/urdf.hpp"

namespace kg::body {

struct RobotBody {
  BodyModel body;
  std::vector<std::string> notes;  // what was taken from the URDF, one line each
  int channels_limited = 0;        // channels with a finite torque limit
};

// Throws std::invalid_argument naming the first joint that differs when `skeleton` is not the
// robot's tree, or check_body_model's message for a link whose inertia is not physical.
RobotBody robot_body_model(const io::Robot& robot, std::shared_ptr<const motion::Skeleton> skeleton,
                           double friction = 0.5, double gravity = 9.81);

}  // namespace kg::body
