#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "kg/motion/kinematics.hpp"
#include "kg/synth/figure.hpp"

using namespace kg;
using namespace kg::synth;

TEST_CASE("the figure has CMU-like joints, ZXY rotations and end sites", "[synth][figure]") {
  const Figure fig = make_figure(1.75);
  const motion::Skeleton& s = *fig.skeleton;
  const std::vector<std::string> names{
      "Hips",      "Spine",       "Chest",       "Neck",          "Head",        "LeftShoulder",
      "LeftArm",   "LeftForeArm", "LeftHand",    "RightShoulder", "RightArm",    "RightForeArm",
      "RightHand", "LeftUpLeg",   "LeftLeg",     "LeftFoot",      "LeftToeBase", "RightUpLeg",
      "RightLeg",  "RightFoot",   "RightToeBase"};
  REQUIRE(s.joint_count() == static_cast<int>(names.size()));
  for (int j = 0; j < s.joint_count(); ++j) CHECK(s.joint(j).name == names[std::size_t(j)]);
  CHECK(s.channel_count() == 6 + 3 * 20);
  CHECK(s.joint(fig.hips).parent == -1);
  using K = motion::ChannelKind;
  const std::vector<K> root{K::Xposition, K::Yposition, K::Zposition,
                            K::Zrotation, K::Xrotation, K::Yrotation};
  for (std::size_t c = 0; c < root.size(); ++c) CHECK(s.joint(fig.hips).channels[c].kind == root[c]);
  for (int j = 1; j < s.joint_count(); ++j) {
    REQUIRE(s.joint(j).channels.size() == 3);
    CHECK(s.joint(j).channels[0].kind == K::Zrotation);
    CHECK(s.joint(j).channels[1].kind == K::Xrotation);
    CHECK(s.joint(j).channels[2].kind == K::Yrotation);
  }
  for (int j = 0; j < s.joint_count(); ++j) {
    const bool tip = j == fig.head || j == fig.hand[kLeft] || j == fig.hand[kRight] || j == fig.toe[kLeft] ||
                     j == fig.toe[kRight];
    CHECK(s.joint(j).end_sites.size() == (tip ? 1u : 0u));
  }
  // The named indices point at the named joints.
  CHECK(s.find_joint("LeftToeBase") == fig.toe[kLeft]);
  CHECK(s.find_joint("RightFoot") == fig.foot[kRight]);
  CHECK(s.find_joint("LeftUpLeg") == fig.up_leg[kLeft]);
  CHECK(s.find_joint("RightHand") == fig.hand[kRight]);
}

TEST_CASE("the figure's proportions follow its stature", "[synth][figure]") {
  for (double H : {1.2, 1.5, 1.75, 2.2}) {
    CAPTURE(H);
    const Figure fig = make_figure(H);
    const motion::Skeleton& s = *fig.skeleton;
    const FigureDimensions& d = fig.dims;
    // Toe tip on the floor to the top of the head: exactly the stature.
    CHECK(s.rest_height() == Approx(H).epsilon(1e-12));
    // The vertical chain of bone lengths adds up to the stature.
    const double chain =
        d.ankle_height + d.shank + d.thigh + d.pelvis_drop + d.spine + d.chest + d.neck + d.head + d.head_top;
    CHECK(chain == Approx(H).epsilon(1e-12));
    CHECK(s.joint(fig.leg[kLeft]).offset.norm() == Approx(0.245 * H));
    CHECK(s.joint(fig.foot[kLeft]).offset.norm() == Approx(0.246 * H));
    CHECK(s.joint(fig.forearm[kRight]).offset.norm() == Approx(0.186 * H));
    CHECK(s.joint(fig.hand[kRight]).offset.norm() == Approx(0.146 * H));
    CHECK(d.foot_length() == Approx(0.152 * H));

    // Rest pose: feet flat (heel and toe tip on the floor), knees at 0.285 H, shoulders 0.815 H.
    std::vector<Eigen::Isometry3d> world(std::size_t(s.joint_count()));
    Eigen::RowVectorXd frame = Eigen::RowVectorXd::Zero(s.channel_count());
    frame.head<3>() = s.joint(fig.hips).offset.transpose();
    motion::forward_kinematics(s, frame, world);
    for (Side side : {kLeft, kRight}) {
      CHECK((world[std::size_t(fig.foot[side])] * fig.heel_local).y() == Approx(0).margin(1e-12));
      CHECK((world[std::size_t(fig.toe[side])] * fig.toe_tip_local).y() == Approx(0).margin(1e-12));
      CHECK(world[std::size_t(fig.foot[side])].translation().y() == Approx(0.039 * H));
      CHECK(world[std::size_t(fig.leg[side])].translation().y() == Approx(0.285 * H));
      CHECK(world[std::size_t(fig.arm[side])].translation().y() == Approx(0.815 * H));
      // The figure faces +Z with its left on +X.
      CHECK(world[std::size_t(fig.arm[side])].translation().x() * side_sign(side) > 0.1 * H);
      CHECK((world[std::size_t(fig.toe[side])] * fig.toe_tip_local).z() >
            world[std::size_t(fig.foot[side])].translation().z());
    }
  }
}

TEST_CASE("a figure of impossible stature is refused", "[synth][figure]") {
  CHECK_THROWS_WITH(make_figure(0.1), Catch::Contains("stature 0.1"));
  CHECK_THROWS_AS(make_figure(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(make_figure(4.0), std::invalid_argument);
}
