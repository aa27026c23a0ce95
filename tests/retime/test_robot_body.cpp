// A robot's own body from its URDF (kg/body/robot_body.hpp): the G1's mass and centre of mass
// against the URDF's inertials placed by its own chain of transforms, effort limits as torque
// limits, a BVH of its tree, a skeleton that is not its tree, and the retime.body_model node.
#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <random>
#include <string>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "../support/urdf_reference.hpp"
#include "kg/body/body_build.hpp"
#include "kg/body/robot_body.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/urdf.hpp"
#include "kg/retime/nodes.hpp"
#include "kg/synth/synthesize.hpp"

namespace fs = std::filesystem;
using namespace kg;

namespace {

const fs::path kG1 = fs::path(KG_DATA_DIR) / "robots" / "unitree_g1" / "g1_29dof.urdf";

bool have_g1() {
  if (fs::exists(kG1)) return true;
  WARN("skipped: " << kG1.string() << " not found (the robot lives in ../shared/data)");
  return false;
}

// The whole robot's centre of mass in URDF base coordinates, from urdfdom's inertials.
Eigen::Vector3d urdf_com(const urdf::ModelInterface& model, const std::map<std::string, double>& q) {
  const auto poses = test::urdf_link_poses(model, q, Eigen::Isometry3d::Identity());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0;
  for (const auto& [name, link] : model.links_) {
    if (!link->inertial) continue;
    const auto& o = link->inertial->origin.position;
    sum += link->inertial->mass * (poses.at(name) * Eigen::Vector3d(o.x, o.y, o.z));
    mass += link->inertial->mass;
  }
  return sum / mass;
}

}  // namespace

TEST_CASE("the G1's body: its links' masses where its URDF puts them, its efforts as torque limits") {
  if (!have_g1()) return;
  const io::Robot g1 = io::read_urdf(kG1.string());
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(kG1.string());
  REQUIRE(model);
  const body::RobotBody built = body::robot_body_model(g1, g1.skeleton);
  const body::BodyModel& body = built.body;
  CHECK(body.total_mass() == Approx(g1.total_mass()));
  CHECK(body.gravity.isApprox(Eigen::Vector3d(0, -9.81, 0)));
  CHECK(built.channels_limited == 29);
  const io::RobotDof& knee = g1.dofs[static_cast<std::size_t>(g1.find_dof("left_knee_joint"))];
  CHECK(body.torque_max[knee.channel] == model->getJoint("left_knee_joint")->limits->effort);
  CHECK(body.torque_min[knee.channel] == -model->getJoint("left_knee_joint")->limits->effort);
  for (int c = 0; c < 6; ++c) {
    CHECK(body.torque_min[c] == 0);
    CHECK(body.torque_max[c] == 0);
  }
  // The centre of mass at random joint positions, in world coordinates (Y up).
  std::mt19937 rng(2);
  for (int trial = 0; trial < 10; ++trial) {
    std::map<std::string, double> q;
    Eigen::RowVectorXd frame = Eigen::RowVectorXd::Zero(g1.skeleton->channel_count());
    for (const io::RobotDof& d : g1.dofs) {
      q[d.name] = std::uniform_real_distribution<double>(d.lower, d.upper)(rng);
      frame[d.channel] = q[d.name];
    }
    const Eigen::Vector3d expected = g1.skeleton->file_to_world * urdf_com(*model, q);
    CHECK((body::body_com(body, frame) - expected).norm() < 1e-12);
  }
}

TEST_CASE("a BVH of the G1's tree gets its body without torque limits, and another skeleton is refused") {
  if (!have_g1()) return;
  const io::Robot g1 = io::read_urdf(kG1.string());
  motion::Motion rest{g1.skeleton, motion::FrameMatrix::Zero(2, g1.skeleton->channel_count()), 30.0, "g1"};
  test::TempDir dir;
  const fs::path bvh = dir.write("g1.bvh", io::write_bvh_string(rest, {.units = "cm", .precision = 9}));
  const io::ImportedMotion back = io::import_bvh(bvh, {.units = "cm", .up = "z", .trim = "none"});
  const body::RobotBody built = body::robot_body_model(g1, back.motion.skeleton);
  CHECK(built.body.total_mass() == Approx(g1.total_mass()));
  CHECK(built.channels_limited == 0);
  REQUIRE(built.notes.size() == 2);
  CHECK_THAT(built.notes[1], Catch::Contains("unlimited"));
  CHECK((body::body_com(built.body, back.motion.values.row(0)) -
         body::body_com(body::robot_body_model(g1, g1.skeleton).body, rest.values.row(0)))
            .norm() < 1e-8);

  // A skeleton that is not the robot's.
  auto other = std::make_shared<motion::Skeleton>(*g1.skeleton);
  other->joint_mut(4).offset.x() += 0.01;
  CHECK_THROWS_WITH(body::robot_body_model(g1, other),
                    Catch::Contains("10 mm from where robot") && Catch::Contains(g1.skeleton->joint(4).name));
  const synth::Synthesis walk = synth::synthesize_walk({.steps = 2, .fps = 30});
  CHECK_THROWS_WITH(body::robot_body_model(g1, walk.motion.skeleton), Catch::Contains("not its tree"));
}

TEST_CASE("retime.body_model with a .urdf file builds the robot's own body") {
  if (!have_g1()) return;
  const io::Robot g1 = io::read_urdf(kG1.string());
  const graph::Registry registry = test::registry_of(retime_body_node_types());
  const motion::Motion rest{g1.skeleton, motion::FrameMatrix::Zero(3, g1.skeleton->channel_count()), 30.0,
                            "g1"};
  test::NodeContext ctx = test::run_node(
      registry, "retime.body_model",
      test::params_for(registry, "retime.body_model", {{"file", kG1.string()}, {"gravity", 1.62}}),
      {{"motion", graph::Value::make(rest)}});
  const body::BodyModel& body = ctx.outputs.at("body").get<body::BodyModel>();
  CHECK(body.total_mass() == Approx(g1.total_mass()));
  CHECK(body.gravity.isApprox(Eigen::Vector3d(0, -1.62, 0)));
  CHECK(std::get<std::string>(ctx.figures.at("table")) == "urdf");
  CHECK(std::get<std::int64_t>(ctx.figures.at("channels_limited")) == 29);
  CHECK(ctx.logged("29 channels limited to the joints' effort"));
}
