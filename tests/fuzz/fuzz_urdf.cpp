// URDF reader (kg/io/urdf.hpp) under fuzzing. Refused: a placed kg::Error. Accepted: a consistent
// skeleton whose links and degrees of freedom map onto its joints and channels, with limits in
// order and finite masses, whose zero pose and a pose at every lower limit write as robot CSV.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "kg/io/robot_motion.hpp"
#include "kg/io/urdf.hpp"

namespace {

using kg::fuzz::require;

void check_robot(const kg::io::Robot& robot) {
  require(robot.skeleton != nullptr, "an accepted URDF without a skeleton");
  const kg::motion::Skeleton& s = *robot.skeleton;
  kg::fuzz::check_skeleton(s);
  require(static_cast<int>(robot.links.size()) == s.joint_count(), "links and joints differ in number");
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    const kg::io::RobotLink& l = robot.links[i];
    require(l.joint == static_cast<int>(i), "link " + l.name + " is not its joint's");
    require(std::isfinite(l.mass) && l.mass >= 0 && l.com.allFinite() && l.inertia.allFinite(),
            "link " + l.name + " has a bad inertial");
    require(robot.find_link(l.name) == &l || robot.find_link(l.name)->name == l.name, "find_link");
  }
  int channels = 6;
  for (const kg::io::RobotDof& d : robot.dofs) {
    require(d.joint > 0 && d.joint < s.joint_count(), "dof " + d.name + " has no joint");
    require(s.joint(d.joint).channels.size() == 1, "dof " + d.name + "'s joint has not one channel");
    require(d.channel == s.joint(d.joint).first_channel, "dof " + d.name + " has the wrong channel");
    require(!(d.lower > d.upper) && !std::isnan(d.lower) && !std::isnan(d.upper),
            "dof " + d.name + " limits");
    ++channels;
  }
  require(channels == s.channel_count(), "channels that no dof moves");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kg::fuzz::expect_clean("fuzz.urdf", [&] {
    const kg::io::Robot robot = kg::io::parse_urdf(std::string(kg::fuzz::text(data, size)), "fuzz.urdf");
    check_robot(robot);
    kg::motion::Motion m{robot.skeleton, kg::motion::FrameMatrix::Zero(2, robot.skeleton->channel_count()),
                         30.0, "fuzz"};
    for (const kg::io::RobotDof& d : robot.dofs)
      if (std::isfinite(d.lower)) m.values(1, d.channel) = d.offset + d.sign * d.lower;
    kg::fuzz::check_motion(m);
    const kg::io::RobotTrajectory t = kg::io::robot_trajectory(m);
    require(t.dof_pos.cols() == static_cast<Eigen::Index>(robot.dofs.size()), "a dof column per dof");
    require(t.root_rot.allFinite() && t.dof_pos.allFinite(), "a trajectory that is not finite");
    std::ostringstream csv;
    kg::io::write_robot_csv(csv, t);
  });
  return 0;
}
