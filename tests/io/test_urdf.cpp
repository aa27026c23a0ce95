// URDF robots: the G1 of ../shared/data read and its forward kinematics checked against the
// URDF's own chain of transforms (urdfdom's poses composed here directly), hand-written trees
// with every joint type, robot CSV and JSON, and malformed files refused at their line.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "../support/urdf_reference.hpp"
#include "kg/base/error.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/io/robot_motion.hpp"
#include "kg/io/urdf.hpp"
#include "kg/motion/kinematics.hpp"

namespace fs = std::filesystem;
using kg::io::read_urdf;
using kg::io::Robot;
using kg::test::urdf_link_poses;

namespace {

const fs::path kG1 = fs::path(KG_DATA_DIR) / "robots" / "unitree_g1" / "g1_29dof.urdf";

// Our forward kinematics at `q` and `base`, compared link by link with the URDF's (in base
// coordinates: file_to_world undone); the worst position (m) and rotation (matrix entry) error.
std::pair<double, double> fk_error(const Robot& robot, const urdf::ModelInterface& model,
                                   const std::map<std::string, double>& q, const Eigen::Isometry3d& base) {
  const kg::motion::Skeleton& s = *robot.skeleton;
  Eigen::RowVectorXd frame = Eigen::RowVectorXd::Zero(s.channel_count());
  frame.head<3>() = base.translation().transpose();
  // The root's channels are Z Y X Euler angles, outermost first.
  const Eigen::Vector3d zyx = base.linear().eulerAngles(2, 1, 0);
  frame.segment<3>(3) = zyx.transpose();
  for (const kg::io::RobotDof& d : robot.dofs)
    frame[d.channel] = d.offset + d.sign * (q.count(d.name) ? q.at(d.name) : 0.0);
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  kg::motion::forward_kinematics(s, frame, world);
  const auto expected = urdf_link_poses(model, q, base);
  double pos = 0, rot = 0;
  for (const kg::io::RobotLink& link : robot.links) {
    const Eigen::Isometry3d& ours = world[static_cast<std::size_t>(link.joint)];
    const Eigen::Vector3d p = s.file_to_world.transpose() * ours.translation();
    const Eigen::Matrix3d R = s.file_to_world.transpose() * ours.linear() * link.rest_rotation;
    pos = std::max(pos, (p - expected.at(link.name).translation()).norm());
    rot = std::max(rot, (R - expected.at(link.name).linear()).cwiseAbs().maxCoeff());
  }
  return {pos, rot};
}

// A small robot with every joint type, a joint listed before its parent's, origins turned by rpy.
const std::string kToy = kg::test::read_file(fs::path(KG_SOURCE_DIR) / "tests" / "io" / "data" / "toy.urdf");

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

std::string error_of(const fs::path& path) {
  try {
    read_urdf(path.string());
  } catch (const kg::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE(
    "the G1's links are where its URDF puts them, at zero and at random joint positions and base poses") {
  if (!fs::exists(kG1)) {
    WARN("skipped: " << kG1.string() << " not found (the robot lives in ../shared/data)");
    return;
  }
  const Robot g1 = read_urdf(kG1.string());
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(kG1.string());
  REQUIRE(model);
  CHECK(g1.dofs.size() == 29);
  CHECK(g1.links.size() == model->links_.size());
  CHECK(g1.skeleton->joint(0).name == "pelvis");
  CHECK(g1.dofs.front().name == "left_hip_pitch_joint");
  CHECK(g1.dofs.back().name == "right_wrist_yaw_joint");
  // Limits and efforts as the file states them.
  const kg::io::RobotDof& knee = g1.dofs[static_cast<std::size_t>(g1.find_dof("left_knee_joint"))];
  CHECK(knee.lower == Approx(model->getJoint("left_knee_joint")->limits->lower));
  CHECK(knee.upper == Approx(model->getJoint("left_knee_joint")->limits->upper));
  CHECK(knee.effort == Approx(model->getJoint("left_knee_joint")->limits->effort));
  const auto& channel = g1.skeleton->joint(knee.joint).channels.at(0);
  CHECK(channel.min == knee.lower);
  CHECK(channel.max == knee.upper);
  double mass = 0;
  for (const auto& [name, link] : model->links_)
    if (link->inertial) mass += link->inertial->mass;
  CHECK(g1.total_mass() == Approx(mass));

  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    std::map<std::string, double> q;
    for (const kg::io::RobotDof& d : g1.dofs)
      q[d.name] = trial == 0 ? 0.0 : std::uniform_real_distribution<double>(d.lower, d.upper)(rng);
    Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
    if (trial > 0) {
      base.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
      base.translation() = Eigen::Vector3d::Random();
    }
    const auto [pos, rot] = fk_error(g1, *model, q, base);
    CHECK(pos < 1e-12);
    CHECK(rot < 1e-12);
  }
}

TEST_CASE(
    "a URDF with revolute, continuous, prismatic and fixed joints, listed child first, moves as the URDF "
    "says") {
  kg::test::TempDir dir;
  const fs::path path = dir.write("toy.urdf", kToy);
  const Robot toy = read_urdf(path.string());
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(kToy);
  REQUIRE(model);
  REQUIRE(toy.dofs.size() == 3);
  // The file's order of joints, except that elbow, listed before its parent joint, follows it.
  CHECK(toy.dofs[0].name == "shoulder");
  CHECK(toy.dofs[1].name == "slide");
  CHECK(toy.dofs[2].name == "elbow");
  CHECK(toy.skeleton->find_joint("shoulder") < toy.skeleton->find_joint("elbow"));
  CHECK(toy.find_link("lower")->joint == toy.skeleton->find_joint("elbow"));
  CHECK(toy.find_link("nothing") == nullptr);
  CHECK(toy.dofs[2].type == kg::io::RobotJointType::Continuous);
  CHECK(std::isinf(toy.dofs[2].upper));
  CHECK(toy.dofs[1].type == kg::io::RobotJointType::Prismatic);
  CHECK(toy.dofs[1].sign == -1.0);  // its axis +X turned by pi about Z: -X of the base
  CHECK(toy.skeleton->joint(toy.skeleton->find_joint("mount")).channels.empty());
  CHECK(toy.total_mass() == 2.0);
  CHECK(toy.links[0].com.isApprox(Eigen::Vector3d(0, 0, 0.1)));
  CHECK(toy.dofs[0].effort == 40.0);
  CHECK(toy.dofs[0].velocity == 3.0);

  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_real_distribution<double> u(-1, 1);
    const std::map<std::string, double> q{
        {"elbow", 4 * u(rng)}, {"shoulder", u(rng)}, {"slide", 0.1 * u(rng)}};
    Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
    base.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    base.translation() = Eigen::Vector3d::Random();
    const auto [pos, rot] = fk_error(toy, *model, q, base);
    CHECK(pos < 1e-12);
    CHECK(rot < 1e-12);
  }
}

TEST_CASE("a robot's motion is written as CSV and JSON with the base Z up and each joint's position") {
  kg::test::TempDir dir;
  const fs::path path = dir.write("toy.urdf", kToy);
  const Robot toy = read_urdf(path.string());
  kg::motion::Motion m{toy.skeleton, kg::motion::FrameMatrix::Zero(2, toy.skeleton->channel_count()), 50.0,
                       "toy"};
  m.values(1, 0) = 0.5;   // base x
  m.values(1, 2) = 0.75;  // base z
  m.values(1, 3) = 0.5;   // base yaw (Z rotation, outermost)
  m.values(1, toy.dofs[0].channel) = -0.5;
  m.values(1, toy.dofs[1].channel) = toy.dofs[1].offset + toy.dofs[1].sign * 0.2;
  m.values(1, toy.dofs[2].channel) = 2.5;
  const kg::io::RobotTrajectory t = kg::io::robot_trajectory(m);
  REQUIRE(t.joint_names == std::vector<std::string>{"shoulder", "slide", "elbow"});
  CHECK(t.root_pos.row(1).isApprox(Eigen::RowVector3d(0.5, 0, 0.75)));
  CHECK(t.root_rot.row(1).isApprox(Eigen::RowVector4d(0, 0, std::sin(0.25), std::cos(0.25))));
  CHECK(t.dof_pos(1, 0) == Approx(-0.5));
  CHECK(t.dof_pos(1, 1) == Approx(0.2));
  CHECK(t.dof_pos(1, 2) == Approx(2.5));

  std::ostringstream csv;
  kg::io::write_robot_csv(csv, t, 4);
  std::istringstream lines(csv.str());
  std::string header, first, second;
  std::getline(lines, header);
  std::getline(lines, first);
  std::getline(lines, second);
  CHECK(header == "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw,shoulder,slide,elbow");
  CHECK(first == "0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,1.0000,0.0000,0.0000,0.0000");
  CHECK(second.rfind("0.0200,0.5000,0.0000,0.7500,0.0000,0.0000,0.2474,0.9689,-0.5000,0.2000,2.5000", 0) ==
        0);

  std::ostringstream json;
  kg::io::write_robot_json(json, t);
  CHECK(json.str().find("\"joint_names\":[\"shoulder\",\"slide\",\"elbow\"]") != std::string::npos);
  CHECK(json.str().find("\"fps\":50.0") != std::string::npos);
  CHECK(json.str().find("\"dof_pos\":[[0.0,0.0,0.0],[-0.5,") != std::string::npos);

  // Chosen by extension; a character is refused with the joint that makes it one.
  const kg::io::MotionFormats formats = kg::io::builtin_motion_formats();
  CHECK(kg::io::motion_writer_for("walk.csv", formats)->name == "robot CSV");
  CHECK(kg::io::motion_writer_for("walk.JSON", formats)->name == "robot JSON");
  auto character = std::make_shared<kg::motion::Skeleton>();
  using kg::motion::ChannelKind;
  character->add_joint({.name = "hips",
                        .channels = {{ChannelKind::Xposition},
                                     {ChannelKind::Yposition},
                                     {ChannelKind::Zposition},
                                     {ChannelKind::Zrotation},
                                     {ChannelKind::Xrotation},
                                     {ChannelKind::Yrotation}}});
  character->add_joint(
      {.name = "knee",
       .parent = 0,
       .channels = {{ChannelKind::Zrotation}, {ChannelKind::Xrotation}, {ChannelKind::Yrotation}}});
  const kg::motion::Motion walk{character, kg::motion::FrameMatrix::Zero(1, 9), 30.0, "walk"};
  CHECK_THROWS_WITH(kg::io::robot_trajectory(walk), Catch::Contains("joint 'knee' has 3"));
}

TEST_CASE("the URDF reader reads the robot as a one-frame clip, Z up, by extension") {
  if (!fs::exists(kG1)) {
    WARN("skipped: " << kG1.string() << " not found (the robot lives in ../shared/data)");
    return;
  }
  const kg::io::ImportedMotion in = kg::io::import_motion(kG1.string(), "", {});
  CHECK(in.motion.frame_count() == 1);
  CHECK(in.motion.skeleton->channel_count() == 6 + 29);
  REQUIRE(!in.notes.empty());
  CHECK_THAT(in.notes[0], Catch::Contains("29 degrees of freedom") && Catch::Contains("Z up"));
  // The legs hang below the pelvis: down is -Y in the world.
  const Eigen::MatrixXd p = kg::motion::joint_world_positions(in.motion);
  const int ankle = in.motion.skeleton->find_joint("left_ankle_roll_joint");
  REQUIRE(ankle > 0);
  CHECK(p(0, 3 * ankle + 1) < -0.6);
  CHECK_THROWS_WITH(kg::io::import_motion(kG1.string(), "", {.units = "cm"}), Catch::Contains("in metres"));
}

TEST_CASE("a G1 motion written as BVH plays in any viewer with the same joint positions") {
  if (!fs::exists(kG1)) {
    WARN("skipped: " << kG1.string() << " not found (the robot lives in ../shared/data)");
    return;
  }
  const Robot g1 = read_urdf(kG1.string());
  kg::motion::Motion m{g1.skeleton, kg::motion::FrameMatrix::Zero(10, g1.skeleton->channel_count()), 50.0,
                       "g1"};
  std::mt19937 rng(11);
  for (int f = 0; f < m.frame_count(); ++f) {
    for (int k = 0; k < 3; ++k) m.values(f, k) = std::uniform_real_distribution<double>(-1, 1)(rng);
    for (int k = 3; k < 6; ++k) m.values(f, k) = std::uniform_real_distribution<double>(-3, 3)(rng);
    for (const kg::io::RobotDof& d : g1.dofs)
      m.values(f, d.channel) = std::uniform_real_distribution<double>(d.lower, d.upper)(rng);
  }
  kg::test::TempDir dir;
  const fs::path bvh = dir.write("g1.bvh", kg::io::write_bvh_string(m, {.units = "cm", .precision = 9}));
  const kg::io::ImportedMotion back = kg::io::import_bvh(bvh, {.units = "cm", .up = "z", .trim = "none"});
  REQUIRE(back.motion.frame_count() == m.frame_count());
  REQUIRE(back.motion.skeleton->joint_count() == g1.skeleton->joint_count());
  const Eigen::MatrixXd expected = kg::motion::joint_world_positions(m);
  const Eigen::MatrixXd got = kg::motion::joint_world_positions(back.motion);
  CHECK((expected - got).cwiseAbs().maxCoeff() < 1e-6);  // metres
}

TEST_CASE(
    "a robot CSV reads back onto its URDF as the motion written, and bad rows are refused at their line") {
  if (!fs::exists(kG1)) {
    WARN("skipped: " << kG1.string() << " not found (the robot lives in ../shared/data)");
    return;
  }
  const Robot g1 = read_urdf(kG1.string());
  kg::motion::Motion m{g1.skeleton, kg::motion::FrameMatrix::Zero(12, g1.skeleton->channel_count()), 50.0,
                       "g1"};
  std::mt19937 rng(5);
  for (int f = 0; f < m.frame_count(); ++f) {
    for (int k = 0; k < 3; ++k) m.values(f, k) = std::uniform_real_distribution<double>(-1, 1)(rng);
    for (int k = 3; k < 6; ++k) m.values(f, k) = 0.3 * f + 0.1 * k;  // turning past pi
    for (const kg::io::RobotDof& d : g1.dofs)
      m.values(f, d.channel) = std::uniform_real_distribution<double>(d.lower, d.upper)(rng);
  }
  std::ostringstream csv;
  kg::io::write_robot_csv(csv, kg::io::robot_trajectory(m), 10);
  kg::test::TempDir dir;
  const fs::path file = dir.write("walk.csv", csv.str());
  const kg::io::ImportedMotion back = kg::io::import_motion(file.string(), kG1.string(), {});
  CHECK(back.motion.fps == Approx(50.0).epsilon(1e-9));
  REQUIRE(back.motion.frame_count() == m.frame_count());
  const Eigen::MatrixXd expected = kg::motion::joint_world_positions(m);
  CHECK((kg::motion::joint_world_positions(back.motion) - expected).cwiseAbs().maxCoeff() < 1e-8);
  // The written CSV again from what was read: the same text.
  std::ostringstream again;
  kg::io::write_robot_csv(again, kg::io::robot_trajectory(back.motion), 10);
  CHECK(again.str() == csv.str());
  // Times printed to 6 digits stand for 30 fps exactly, not 30.0001 (resampled to its own rate
  // the clip keeps every frame); an uneven rate stays as the times give it.
  {
    kg::motion::Motion short_clip = kg::motion::frame_range(m, 0, 4);
    short_clip.fps = 30;
    std::ostringstream six;
    kg::io::write_robot_csv(six, kg::io::robot_trajectory(short_clip), 6);
    const fs::path at30 = dir.write("at30.csv", six.str());
    CHECK(kg::io::import_motion(at30.string(), kG1.string(), {}).motion.fps == 30.0);
    short_clip.fps = 29.97002997;
    std::ostringstream ntsc;
    kg::io::write_robot_csv(ntsc, kg::io::robot_trajectory(short_clip), 6);
    const fs::path at_ntsc = dir.write("ntsc.csv", ntsc.str());
    CHECK(kg::io::import_motion(at_ntsc.string(), kG1.string(), {}).motion.fps == 30000.0 / 1001.0);
    short_clip.fps = 31.4;
    std::ostringstream odd;
    kg::io::write_robot_csv(odd, kg::io::robot_trajectory(short_clip), 6);
    const fs::path at_odd = dir.write("odd.csv", odd.str());
    CHECK(kg::io::import_motion(at_odd.string(), kG1.string(), {}).motion.fps == Approx(31.4).epsilon(1e-5));
  }
  // A frame range of the file.
  CHECK(kg::io::import_motion(file.string(), kG1.string(), {.trim = "2..5"}).motion.frame_count() == 4);
  CHECK_THROWS_WITH(kg::io::import_motion(file.string(), "", {}),
                    Catch::Contains("set skeleton to the .urdf"));
  CHECK_THROWS_WITH(kg::io::import_motion(file.string(), kG1.string(), {.units = "cm"}),
                    Catch::Contains("in metres"));
  CHECK_THROWS_WITH(kg::io::import_motion(file.string(), kG1.string(), {.up = "y"}), Catch::Contains("Z up"));

  const std::string text = csv.str();
  const std::size_t second_row = text.find('\n', text.find('\n') + 1) + 1;
  struct Case {
    const char* what;
    std::string text;
    int line;
    const char* says;
  };
  const std::vector<Case> cases{
      {"an unknown joint", replaced(text, "left_knee_joint", "left_kne_joint"), 1,
       "did you mean 'left_knee_joint'"},
      {"a missing base column", replaced(text, "root_qw", "qw"), 1, "to be root_qw"},
      {"a short row", text.substr(0, text.rfind(',')) + "\n", 13, "values as the header"},
      {"not a number",
       replaced(text, text.substr(second_row, text.find(',', second_row) - second_row), "0.02x"), 3,
       "expected a finite number"},
      {"uneven times",
       replaced(text, text.substr(second_row, text.find(',', second_row) - second_row), "0.03"), 3,
       "evenly spaced"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const fs::path bad = dir.write("bad.csv", c.text);
    try {
      kg::io::import_motion(bad.string(), kG1.string(), {});
      FAIL("accepted");
    } catch (const kg::Error& e) {
      CHECK_THAT(e.what(), Catch::Contains(bad.string() + ":" + std::to_string(c.line) + ":") &&
                               Catch::Contains(c.says));
    }
  }
}

TEST_CASE("a malformed URDF is refused naming its file, the line at fault and what was expected") {
  kg::test::TempDir dir;
  struct Case {
    const char* what;
    std::string text;
    int line;
    const char* says;
  };
  const std::vector<Case> cases{
      {"not XML", "<robot name=\"x\">\n<link name=\"a\">\n</robot>\n", 2, "malformed XML"},
      {"not a robot", "<?xml version=\"1.0\"?>\n<model name=\"x\"/>\n", 2, "expected a <robot> element"},
      {"a missing parent link",
       replaced(kToy, "<parent link=\"base\"/><child link=\"upper\"/>",
                "<parent link=\"bsae\"/><child link=\"upper\"/>"),
       16, "bsae"},
      {"a loop: a link with two parents",
       replaced(kToy, "<parent link=\"lower\"/><child link=\"tool\"/>",
                "<parent link=\"lower\"/><child link=\"upper\"/>"),
       8, "Two root links"},
      {"a floating joint below the root",
       replaced(kToy, "name=\"mount\" type=\"fixed\"", "name=\"mount\" type=\"floating\""), 28,
       "only the root link floats"},
      {"reversed limits", replaced(kToy, "lower=\"-1\" upper=\"2\"", "lower=\"2\" upper=\"-1\""), 16,
       "lower <= upper"},
      {"a skew prismatic joint", replaced(kToy, "rpy=\"0 0 3.141592653589793\"", "rpy=\"0 0 0.5\""), 22,
       "not an axis of the base frame"},
      {"a link without a name (a fuzz finding)", replaced(kToy, "<link name=\"upper\"/>", "<link/>"), 0,
       "<link> without a name"},
      {"a negative mass", replaced(kToy, "<mass value=\"2\"/>", "<mass value=\"-2\"/>"), 8, "mass"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const fs::path path = dir.write("bad.urdf", c.text);
    const std::string message = error_of(path);
    CHECK_THAT(message, Catch::Contains(path.string()) && Catch::Contains(c.says));
    if (c.line > 0) CHECK_THAT(message, Catch::Contains(path.string() + ":" + std::to_string(c.line) + ":"));
  }
  CHECK_THAT(error_of(dir / "missing.urdf"), Catch::Contains("missing.urdf"));
}
