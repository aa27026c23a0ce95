// A robot's body from its URDF (robot_body.hpp).
#include "kg/body/robot_body.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/base/text.hpp"
#include "kg/body/body_build.hpp"

namespace kg::body {

RobotBody robot_body_model(const io::Robot& robot, std::shared_ptr<const motion::Skeleton> skeleton,
                           double friction, double gravity) {
  const motion::Skeleton& r = *robot.skeleton;
  const motion::Skeleton& s = *skeleton;
  const std::string who = text::shown_path(robot.path);
  if (s.joint_count() != r.joint_count())
    throw std::invalid_argument("the motion's skeleton has " + std::to_string(s.joint_count()) +
                                " joints, robot " + who + " " + std::to_string(r.joint_count()) +
                                ": not its tree");
  for (int j = 0; j < r.joint_count(); ++j) {
    const motion::Joint& a = s.joint(j);
    const motion::Joint& b = r.joint(j);
    if (a.name != b.name || a.parent != b.parent)
      throw std::invalid_argument("the motion's joint " + std::to_string(j) + " is " + text::excerpt(a.name) +
                                  ", robot " + who + "'s is " + text::excerpt(b.name) + ": not its tree");
    if ((a.offset - b.offset).norm() > 1e-6)
      throw std::invalid_argument("joint " + text::excerpt(a.name) + " rests " +
                                  text::significant((a.offset - b.offset).norm() * 1000, 4) +
                                  " mm from where robot " + who + " puts it: not its tree");
  }
  RobotBody out;
  BodyModel& body = out.body;
  body.skeleton = std::move(skeleton);
  body.friction = friction;
  body.gravity = Eigen::Vector3d(0, -gravity, 0);
  body.segments.resize(static_cast<std::size_t>(r.joint_count()));
  body.segment_class.assign(static_cast<std::size_t>(r.joint_count()), "");
  for (const io::RobotLink& link : robot.links) {
    SegmentInertia& seg = body.segments[static_cast<std::size_t>(link.joint)];
    seg.mass = link.mass;
    seg.com = link.com;
    seg.inertia = link.inertia;
    if (link.mass > 0) body.segment_class[static_cast<std::size_t>(link.joint)] = "link " + link.name;
  }
  const double inf = std::numeric_limits<double>::infinity();
  body.torque_min = Eigen::VectorXd::Constant(s.channel_count(), -inf);
  body.torque_max = Eigen::VectorXd::Constant(s.channel_count(), inf);
  const motion::Joint& root = s.joint(0);
  for (std::size_t k = 0; k < root.channels.size(); ++k) {
    body.torque_min[root.first_channel + static_cast<int>(k)] = 0;
    body.torque_max[root.first_channel + static_cast<int>(k)] = 0;
  }
  int unlimited_multi = 0;
  for (const io::RobotDof& d : robot.dofs) {
    const motion::Joint& j = s.joint(d.joint);
    if (j.channels.size() != 1) {
      ++unlimited_multi;
      continue;
    }
    if (d.effort > 0) {
      body.torque_min[j.first_channel] = -d.effort;
      body.torque_max[j.first_channel] = d.effort;
      ++out.channels_limited;
    }
  }
  check_body_model(body, "robot " + who);
  out.notes.push_back("body from robot " + who + ": " + text::significant(body.total_mass(), 5) + " kg in " +
                      std::to_string(robot.links.size()) + " links, the URDF's inertials; " +
                      std::to_string(out.channels_limited) + " channels limited to the joints' effort");
  if (unlimited_multi > 0)
    out.notes.push_back(std::to_string(unlimited_multi) +
                        " joints have more than one channel (a BVH of the robot's tree?): their torques are "
                        "unlimited, as their channels are not the actuated axis; read the motion as the "
                        "robot's CSV (skeleton: the .urdf) to have the effort limits");
  return out;
}

}  // namespace kg::body
