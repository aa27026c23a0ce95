#include <catch2/catch.hpp>

#include <random>

#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"
#include "motion_test_util.hpp"

using namespace kg::motion;
using kg::motion::test::channels_of;
using kg::motion::test::kPi;
using kg::motion::test::mixed_skeleton;
using kg::motion::test::random_frame;
using kg::motion::test::rotations_in;
using K = ChannelKind;

namespace {

using Jacobian = Eigen::Matrix<double, 3, Eigen::Dynamic>;

std::vector<Eigen::Isometry3d> fk(const Skeleton& s, const Eigen::RowVectorXd& frame) {
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  forward_kinematics(s, frame, world);
  return world;
}

Eigen::Matrix3d aa(double angle, int axis) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

// Root with a child one unit along its X: the child's world position shows the root rotation.
std::shared_ptr<Skeleton> two_joints(std::vector<ChannelKind> root_channels,
                                     Eigen::Vector3d root_offset = {0, 0, 0}) {
  auto s = std::make_shared<Skeleton>();
  Joint root;
  root.name = "root";
  root.offset = root_offset;
  root.channels = channels_of(root_channels);
  s->add_joint(root);
  Joint child;
  child.name = "child";
  child.parent = 0;
  child.offset = {1, 0, 0};
  s->add_joint(child);
  return s;
}

}  // namespace

TEST_CASE("FK of one joint rotating in each order matches hand-built rotations", "[kinematics]") {
  const double a = 0.3, b = -0.7, c = 1.1;
  for (std::string order : {"XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "ZXZ", "YX", "Z"}) {
    const auto s = two_joints(rotations_in(order), {0.5, 1.0, -2.0});
    Eigen::RowVectorXd f(s->channel_count());
    const double values[3] = {a, b, c};
    for (int i = 0; i < f.size(); ++i) f[i] = values[i];
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    for (std::size_t i = 0; i < order.size(); ++i)
      R = R * aa(values[i], order[i] - 'X');  // first is outermost
    const auto world = fk(*s, f);
    INFO("order " << order);
    CHECK((world[0].linear() - R).norm() < 1e-14);
    CHECK((world[0].translation() - Eigen::Vector3d(0.5, 1.0, -2.0)).norm() < 1e-14);
    CHECK((world[1].translation() - (Eigen::Vector3d(0.5, 1.0, -2.0) + R.col(0))).norm() < 1e-14);
    CHECK((world[1].linear() - R).norm() < 1e-14);
    CHECK((world[1].matrix().row(3) - Eigen::RowVector4d(0, 0, 0, 1)).isZero(0));
  }
}

TEST_CASE("FK: a hand-computed root translation and quarter turn", "[kinematics]") {
  const auto s = two_joints({K::Xposition, K::Yposition, K::Zposition, K::Zrotation});
  Eigen::RowVectorXd f(4);
  f << 1, 2, 3, kPi / 2;
  const auto world = fk(*s, f);
  // The child, one unit along the root's X, turned 90 degrees about Z: one unit along world Y.
  CHECK((world[1].translation() - Eigen::Vector3d(1, 3, 3)).norm() < 1e-15);
}

TEST_CASE("FK: position channels replace the matching offset component, they do not add", "[kinematics]") {
  // Root offset (10, 20, 30) and only an Xposition channel: X comes from the channel, Y and Z from
  // the offset (as Blender and MotionBuilder read BVH).
  const auto s = two_joints({K::Xposition, K::Yrotation}, {10, 20, 30});
  Eigen::RowVectorXd f(2);
  f << 5, 0;
  CHECK((fk(*s, f)[0].translation() - Eigen::Vector3d(5, 20, 30)).norm() < 1e-15);

  // A non-root joint with all three position channels (the Bandai Namco layout) ignores its offset.
  auto t = std::make_shared<Skeleton>();
  Joint root;
  root.name = "root";
  root.channels = channels_of({K::Zrotation});
  t->add_joint(root);
  Joint arm;
  arm.name = "arm";
  arm.parent = 0;
  arm.offset = {1, 0, 0};
  arm.channels =
      channels_of({K::Xposition, K::Yposition, K::Zposition, K::Zrotation, K::Yrotation, K::Xrotation});
  t->add_joint(arm);
  Eigen::RowVectorXd g(7);
  g << kPi / 2, 0, 2, 0, 0, 0, 0;
  CHECK((fk(*t, g)[1].translation() - Eigen::Vector3d(-2, 0, 0)).norm() < 1e-15);  // Rz(90) (0, 2, 0)
  // Values equal to the offset reproduce the plain offset.
  g << kPi / 2, 1, 0, 0, 0, 0, 0;
  CHECK((fk(*t, g)[1].translation() - Eigen::Vector3d(0, 1, 0)).norm() < 1e-15);
}

TEST_CASE("FK: an ASF axis sets the frame the channels rotate in", "[kinematics]") {
  // axis = Rz(90 deg): the bone's local X is world Y, so rx turns about world Y.
  auto s = std::make_shared<Skeleton>();
  Joint root;
  root.name = "root";
  root.axis = aa(kPi / 2, 2);
  root.channels = channels_of({K::Xrotation});
  s->add_joint(root);
  Joint tip;
  tip.name = "tip";
  tip.parent = 0;
  tip.offset = {1, 0, 0};  // offsets stay in the parent-aligned frame, not the axis frame
  s->add_joint(tip);
  Eigen::RowVectorXd f(1);
  f << kPi / 2;
  const auto world = fk(*s, f);
  CHECK((world[0].linear() - aa(kPi / 2, 1)).norm() < 1e-15);
  CHECK((world[1].translation() - Eigen::Vector3d(0, 0, -1)).norm() < 1e-15);  // Ry(90) x = -z
  // Zero angles: the axis has no effect at all.
  f << 0;
  CHECK(fk(*s, f)[0].linear().isIdentity(1e-15));
}

TEST_CASE("FK: file_to_world turns a Z-up file into Y-up world coordinates", "[kinematics]") {
  auto s = two_joints({K::Xposition, K::Yposition, K::Zposition, K::Zrotation});
  s->file_to_world = aa(-kPi / 2, 0);
  Eigen::RowVectorXd f(4);
  f << 0, 0, 1, kPi / 2;  // one unit up (file Z), turned about the vertical
  const auto world = fk(*s, f);
  CHECK((world[0].translation() - Eigen::Vector3d(0, 1, 0)).norm() < 1e-15);
  // The child at file (0, 1, 1) -> world (0, 1, -1).
  CHECK((world[1].translation() - Eigen::Vector3d(0, 1, -1)).norm() < 1e-15);
}

TEST_CASE("FK composes local transforms down the tree", "[kinematics]") {
  const auto s = mixed_skeleton();
  std::mt19937 rng(1);
  for (int t = 0; t < 10; ++t) {
    const Eigen::RowVectorXd f = random_frame(*s, rng);
    const auto world = fk(*s, f);
    for (int j = 0; j < s->joint_count(); ++j) {
      const int p = s->joint(j).parent;
      Eigen::Isometry3d parent = Eigen::Isometry3d::Identity();
      if (p >= 0)
        parent = world[static_cast<std::size_t>(p)];
      else
        parent.linear() = s->file_to_world;
      const Eigen::Isometry3d expected = parent * local_transform(*s, j, f);
      INFO("joint " << s->joint(j).name);
      CHECK((world[static_cast<std::size_t>(j)].matrix() - expected.matrix()).cwiseAbs().maxCoeff() < 1e-13);
      // Rotations stay rotations.
      CHECK((world[static_cast<std::size_t>(j)].linear() *
             world[static_cast<std::size_t>(j)].linear().transpose())
                .isIdentity(1e-12));
    }
  }
}

TEST_CASE("FK and Jacobians refuse buffers of the wrong size", "[kinematics]") {
  const auto s = mixed_skeleton();
  Eigen::RowVectorXd f = Eigen::RowVectorXd::Zero(s->channel_count());
  Eigen::RowVectorXd short_frame = Eigen::RowVectorXd::Zero(s->channel_count() - 1);
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s->joint_count()));
  std::vector<Eigen::Isometry3d> small(3);
  CHECK_THROWS_WITH(forward_kinematics(*s, short_frame, world), Catch::Contains("frame has"));
  CHECK_THROWS_WITH(forward_kinematics(*s, f, small), Catch::Contains("3 world transforms for 14 joints"));
  forward_kinematics(*s, f, world);
  Jacobian J(3, s->channel_count());
  Jacobian narrow(3, 4);
  CHECK_THROWS_WITH(point_jacobian(*s, f, world, 0, Eigen::Vector3d::Zero(), narrow),
                    Catch::Contains("columns"));
  CHECK_THROWS_AS(point_jacobian(*s, f, world, 99, Eigen::Vector3d::Zero(), J), std::out_of_range);
  CHECK_THROWS_AS(local_transform(*s, -1, f), std::out_of_range);
  CHECK_THROWS_AS(influencing_channels(*s, 14), std::out_of_range);
}

TEST_CASE("point Jacobians match central finite differences on random poses", "[kinematics][jacobian]") {
  const auto s = mixed_skeleton();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> coord(-0.3, 0.3);
  const int n = s->channel_count();
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s->joint_count()));
  std::vector<Eigen::Isometry3d> wp(world.size()), wm(world.size());
  Jacobian J(3, n), fd(3, n);
  const double h = 1e-6;
  double worst = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::RowVectorXd f = random_frame(*s, rng);
    forward_kinematics(*s, f, world);
    for (int joint = 0; joint < s->joint_count(); ++joint) {
      const Eigen::Vector3d local(coord(rng), coord(rng), coord(rng));
      J.setConstant(123.0);  // every column must be written
      point_jacobian(*s, f, world, joint, local, J);
      for (int c = 0; c < n; ++c) {
        Eigen::RowVectorXd fp = f, fm = f;
        fp[c] += h;
        fm[c] -= h;
        forward_kinematics(*s, fp, wp);
        forward_kinematics(*s, fm, wm);
        fd.col(c) =
            (wp[static_cast<std::size_t>(joint)] * local - wm[static_cast<std::size_t>(joint)] * local) /
            (2 * h);
      }
      const double err = (J - fd).cwiseAbs().maxCoeff();
      worst = std::max(worst, err);
      INFO("trial " << trial << " joint " << s->joint(joint).name);
      REQUIRE(err < 1e-6);
      // Non-zero columns only among the influencing channels, all of which are listed.
      const std::vector<int> infl = influencing_channels(*s, joint);
      std::vector<bool> is_infl(static_cast<std::size_t>(n), false);
      for (int c : infl) is_infl[static_cast<std::size_t>(c)] = true;
      for (int c = 0; c < n; ++c)
        if (!is_infl[static_cast<std::size_t>(c)]) REQUIRE(J.col(c).isZero(0));
    }
  }
  CHECK(worst < 1e-6);
  WARN("worst |J - finite differences| = " << worst);
}

TEST_CASE("influencing channels are the chain's, increasing", "[kinematics]") {
  const auto s = mixed_skeleton();
  const int lhand = s->find_joint("lhand");
  const std::vector<int> ch = influencing_channels(*s, lhand);
  REQUIRE(std::is_sorted(ch.begin(), ch.end()));
  std::vector<int> expected;
  for (const char* name : {"root", "spine", "chest", "lshoulder", "lelbow", "lhand"}) {
    const Joint& j = s->joint(s->find_joint(name));
    for (int c = 0; c < static_cast<int>(j.channels.size()); ++c) expected.push_back(j.first_channel + c);
  }
  CHECK(ch == expected);
  CHECK(influencing_channels(*s, 0).size() == 6);
}

TEST_CASE("joint_world_positions lists every joint origin per frame", "[kinematics]") {
  const auto s = mixed_skeleton();
  std::mt19937 rng(9);
  Motion m{s, FrameMatrix(5, s->channel_count()), 60.0, "x"};
  for (int f = 0; f < 5; ++f) m.values.row(f) = random_frame(*s, rng);
  const Eigen::MatrixXd P = joint_world_positions(m);
  REQUIRE(P.rows() == 5);
  REQUIRE(P.cols() == 3 * s->joint_count());
  for (int f = 0; f < 5; ++f) {
    const auto world = fk(*s, m.values.row(f));
    for (int j = 0; j < s->joint_count(); ++j)
      CHECK((P.block<1, 3>(f, 3 * j).transpose() - world[static_cast<std::size_t>(j)].translation()).norm() ==
            0);
  }
}

TEST_CASE("joint_rotation is the local rotation, set_joint_rotation writes it back nearest", "[kinematics]") {
  const auto s = mixed_skeleton();
  std::mt19937 rng(21);
  for (int t = 0; t < 20; ++t) {
    const Eigen::RowVectorXd f = random_frame(*s, rng);
    for (int j = 0; j < s->joint_count(); ++j) {
      const Joint& jt = s->joint(j);
      INFO("joint " << jt.name);
      const Eigen::Matrix3d R = joint_rotation(*s, j, f);
      CHECK((R - local_transform(*s, j, f).linear()).cwiseAbs().maxCoeff() < 1e-14);
      // Start from the angles a whole turn (plus a little) away: they come back a turn away,
      // giving the same rotation; the position channels are untouched.
      Eigen::RowVectorXd g = f;
      const auto idx = rotation_channel_indices(jt);
      const int n = rotation_order(jt).count;
      for (int r = 0; r < n; ++r) g[jt.first_channel + idx[static_cast<std::size_t>(r)]] += 2 * kPi + 0.01;
      set_joint_rotation(*s, j, R, g);
      CHECK((joint_rotation(*s, j, g) - R).cwiseAbs().maxCoeff() < 1e-9);
      for (int r = 0; r < n; ++r) {
        const int c = jt.first_channel + idx[static_cast<std::size_t>(r)];
        CHECK(g[c] == Approx(f[c] + 2 * kPi).margin(1e-9));
      }
      for (int c = 0; c < s->channel_count(); ++c)
        if (s->channel_owner(c).first != j) CHECK(g[c] == f[c]);
    }
  }
  Eigen::RowVectorXd f = Eigen::RowVectorXd::Zero(s->channel_count());
  CHECK_THROWS_AS(joint_rotation(*s, 99, f), std::out_of_range);
  Eigen::RowVectorXd short_frame(3);
  CHECK_THROWS_WITH(set_joint_rotation(*s, 0, Eigen::Matrix3d::Identity(), short_frame),
                    Catch::Contains("frame has 3 values"));
}
