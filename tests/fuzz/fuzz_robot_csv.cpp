// Robot CSV reader (kg/io/robot_motion.hpp) under fuzzing, on a robot of its own (a revolute, a
// prismatic and a continuous joint). Refused: a placed kg::Error. Accepted: a consistent motion
// on the robot's skeleton, at a finite positive rate, that writes as robot CSV again.
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "kg/io/robot_motion.hpp"
#include "kg/io/urdf.hpp"

namespace {

const kg::io::Robot& robot() {
  static const kg::io::Robot r = kg::io::parse_urdf(
      "<robot name=\"r\"><link name=\"base\"/><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>"
      "<joint name=\"hinge\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/>"
      "<origin xyz=\"0 0 -0.4\" rpy=\"0 0 1.5707963267948966\"/><axis xyz=\"0 1 0\"/>"
      "<limit lower=\"-1\" upper=\"1\" effort=\"10\" velocity=\"2\"/></joint>"
      "<joint name=\"slide\" type=\"prismatic\"><parent link=\"a\"/><child link=\"b\"/>"
      "<axis xyz=\"0 0 1\"/><limit lower=\"0\" upper=\"0.2\" effort=\"10\" velocity=\"2\"/></joint>"
      "<joint name=\"spin\" type=\"continuous\"><parent link=\"b\"/><child link=\"c\"/>"
      "<axis xyz=\"1 0 0\"/></joint></robot>",
      "robot.urdf");
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const kg::io::Robot& r = robot();
  kg::fuzz::expect_clean("fuzz.csv", [&] {
    const kg::motion::Motion m =
        kg::io::parse_robot_csv(std::string(kg::fuzz::text(data, size)), "fuzz.csv", r);
    kg::fuzz::require(m.skeleton == r.skeleton, "a motion on another skeleton");
    kg::fuzz::check_motion(m);
    std::ostringstream csv;
    kg::io::write_robot_csv(csv, kg::io::robot_trajectory(m));
  });
  return 0;
}
