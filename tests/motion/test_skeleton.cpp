#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "kg/motion/motion.hpp"
#include "kg/motion/skeleton.hpp"
#include "motion_test_util.hpp"

using namespace kg::motion;
using kg::motion::test::channels_of;
using kg::motion::test::kPi;
using K = ChannelKind;

namespace {

Joint joint(const std::string& name, int parent, std::vector<ChannelKind> kinds,
            Eigen::Vector3d offset = Eigen::Vector3d::Zero()) {
  Joint j;
  j.name = name;
  j.parent = parent;
  j.offset = offset;
  j.channels = channels_of(kinds);
  return j;
}

}  // namespace

TEST_CASE("channel kinds print as BVH names and parse back", "[skeleton]") {
  for (int k = 0; k < 6; ++k) {
    const auto kind = static_cast<ChannelKind>(k);
    CHECK(channel_kind_from_string(to_string(kind)) == kind);
  }
  CHECK(std::string(to_string(K::Zrotation)) == "Zrotation");
  CHECK(channel_kind_from_string("XPOSITION") == K::Xposition);  // as Blender reads them
  CHECK_FALSE(channel_kind_from_string("Xrot").has_value());
  CHECK_FALSE(channel_kind_from_string("").has_value());
  CHECK_FALSE(channel_kind_from_string("Xrotations").has_value());
  CHECK(is_rotation(K::Xrotation));
  CHECK_FALSE(is_rotation(K::Zposition));
  CHECK(axis_index(K::Yrotation) == 1);
  CHECK(axis_index(K::Zposition) == 2);
}

TEST_CASE("add_joint numbers channels, lookups find joints and channels", "[skeleton]") {
  Skeleton s;
  CHECK(s.add_joint(joint(
            "hip", -1,
            {K::Xposition, K::Yposition, K::Zposition, K::Zrotation, K::Xrotation, K::Yrotation})) == 0);
  CHECK(s.add_joint(joint("spine", 0, {})) == 1);  // no channels: shares first_channel with the next
  CHECK(s.add_joint(joint("chest", 1, {K::Xrotation})) == 2);
  CHECK(s.add_joint(joint("tip", 2, {})) == 3);
  CHECK(s.add_joint(joint("lthigh", 0, {K::Yrotation, K::Xposition})) == 4);
  CHECK(s.joint_count() == 5);
  CHECK(s.channel_count() == 9);
  CHECK(s.joint(1).first_channel == 6);
  CHECK(s.joint(2).first_channel == 6);
  CHECK(s.joint(4).first_channel == 7);
  CHECK(s.find_joint("chest") == 2);
  CHECK(s.find_joint("Chest") == -1);
  CHECK(s.channel_owner(0) == std::pair{0, 0});
  CHECK(s.channel_owner(5) == std::pair{0, 5});
  CHECK(s.channel_owner(6) == std::pair{2, 0});
  CHECK(s.channel_owner(8) == std::pair{4, 1});
  CHECK(s.channel_name(3) == "hip.Zrotation");
  CHECK(s.channel_name(6) == "chest.Xrotation");
  CHECK(s.channel_name(8) == "lthigh.Xposition");
  CHECK_THROWS_AS(s.channel_owner(9), std::out_of_range);
  CHECK_THROWS_AS(s.channel_owner(-1), std::out_of_range);
  CHECK_THROWS_AS(s.channel_name(9), std::out_of_range);
}

TEST_CASE("add_joint refuses bad joints with a message naming them", "[skeleton]") {
  Skeleton s;
  s.add_joint(joint("root", -1, {K::Xposition, K::Yposition, K::Zposition, K::Xrotation}));
  struct Case {
    const char* what;
    Joint j;
    const char* message;
  };
  Joint no_name = joint("", 0, {});
  Joint four_rot = joint("a", 0, {K::Xrotation, K::Yrotation, K::Zrotation, K::Xrotation});
  Joint same_axes = joint("b", 0, {K::Xrotation, K::Xposition, K::Xrotation});
  Joint two_pos = joint("c", 0, {K::Yposition, K::Xrotation, K::Yposition});
  Joint limits = joint("d", 0, {K::Xrotation});
  limits.channels[0].min = 1;
  limits.channels[0].max = -1;
  Joint nan_limit = joint("e", 0, {K::Xrotation});
  nan_limit.channels[0].min = std::numeric_limits<double>::quiet_NaN();
  Joint skew = joint("f", 0, {K::Xrotation});
  skew.axis(0, 1) = 0.5;
  Joint mirror = joint("g", 0, {K::Xrotation});
  mirror.axis(0, 0) = -1;
  Joint nan_offset = joint("h", 0, {}, {0, std::nan(""), 0});
  Joint bad_site = joint("i", 0, {});
  bad_site.end_sites.push_back({0, std::numeric_limits<double>::infinity(), 0});
  Joint bad_kind = joint("k", 0, {});
  bad_kind.channels.push_back({static_cast<ChannelKind>(9)});
  const std::vector<Case> cases = {
      {"parent out of range", joint("x", 1, {}), "joint 'x': parent 1 does not exist (expected -1 or 0..0)"},
      {"negative parent", joint("x", -2, {}), "parent -2 does not exist"},
      {"duplicate name", joint("root", 0, {}), "joint 'root': duplicate joint name"},
      {"no name", no_name, "has no name"},
      {"four rotations", four_rot, "joint 'a': rotation order 'XYZX': at most 3 axes"},
      {"neighbouring equal rotation axes", same_axes, "joint 'b': rotation order 'XX': two neighbouring"},
      {"position channel twice", two_pos, "joint 'c': channel Yposition appears twice"},
      {"min > max", limits, "joint 'd': channel Xrotation has limits [1.000000, -1.000000]"},
      {"NaN limit", nan_limit, "joint 'e': channel Xrotation has limits"},
      {"non-orthonormal axis", skew, "joint 'f': axis is not a rotation matrix"},
      {"reflection axis", mirror, "joint 'g': axis is not a rotation matrix"},
      {"NaN offset", nan_offset, "joint 'h': offset"},
      {"infinite end site", bad_site, "joint 'i': end site"},
      {"invalid channel kind", bad_kind, "joint 'k': invalid channel kind 9"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    CHECK_THROWS_WITH(s.add_joint(c.j), Catch::Contains(c.message));
  }
  // Nothing of the refused joints stayed.
  CHECK(s.joint_count() == 1);
  CHECK(s.channel_count() == 4);
}

TEST_CASE("the name index follows copies and refused joints, and stays fast on many joints", "[skeleton]") {
  Skeleton s;
  s.add_joint(joint("root", -1, {K::Xrotation}));
  for (int j = 1; j < 200000; ++j) s.add_joint(joint("j" + std::to_string(j), 0, {K::Yrotation}));
  CHECK_THROWS_WITH(s.add_joint(joint("j199999", 0, {})), "joint 'j199999': duplicate joint name");
  CHECK_THROWS_WITH(s.add_joint(joint("late", 7, {K::Xrotation, K::Xrotation})),
                    Catch::Contains("joint 'late': rotation order"));
  CHECK(s.find_joint("late") == -1);  // a refused joint is not indexed
  CHECK(s.joint_count() == 200000);
  CHECK(s.channel_count() == 200000);
  const Skeleton copy = s;
  s.add_joint(joint("late", 7, {}));
  CHECK(s.find_joint("late") == 200000);
  CHECK(copy.find_joint("late") == -1);
  CHECK(copy.find_joint("j123456") == 123456);
  CHECK(copy.find_joint("root") == 0);
}

TEST_CASE("rest height is the vertical extent of joints and end sites in world Y", "[skeleton]") {
  Skeleton s;
  CHECK(s.rest_height() == 0);
  s.add_joint(joint("hips", -1, {K::Xposition, K::Yposition, K::Zposition}, {5, 0.95, 7}));
  s.add_joint(joint("head", 0, {K::Xrotation}, {0, 0.7, 0}));
  s.joint_mut(1).end_sites.push_back({0, 0.1, 0});
  s.add_joint(joint("foot", 0, {K::Xrotation}, {0.1, -0.9, 0.1}));
  CHECK(s.rest_height() == Approx(0.7 + 0.1 + 0.9));
  // A Z-up file: the same figure lying along Z reports the same height once file_to_world says so.
  Skeleton z;
  z.add_joint(joint("hips", -1, {}, {0, 0, 0.95}));
  z.add_joint(joint("head", 0, {}, {0, 0, 0.8}));
  z.add_joint(joint("foot", 0, {}, {0, 0.3, -0.9}));
  CHECK(z.rest_height() == Approx(0.3));
  z.file_to_world = Eigen::AngleAxisd(-kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  CHECK(z.rest_height() == Approx(1.7));
}

TEST_CASE("Motion::check refuses inconsistent clips with what is wrong", "[motion]") {
  auto s = std::make_shared<Skeleton>();
  s->add_joint(joint("hip", -1, {K::Yposition, K::Xrotation}));
  s->add_joint(joint("knee", 0, {K::Xrotation}));
  Motion m{s, FrameMatrix::Zero(4, 3), 120.0, "walk"};
  CHECK_NOTHROW(m.check());
  CHECK(m.frame_count() == 4);
  CHECK(m.duration() == Approx(3.0 / 120));

  Motion no_skeleton = m;
  no_skeleton.skeleton.reset();
  CHECK_THROWS_WITH(no_skeleton.check(), "motion 'walk': no skeleton");
  Motion wrong_cols{s, FrameMatrix::Zero(4, 5), 120.0, "walk"};
  CHECK_THROWS_WITH(wrong_cols.check(), "motion 'walk': 5 values per frame, but the skeleton has 3 channels");
  for (double fps : {0.0, -30.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    Motion bad = m;
    bad.fps = fps;
    INFO("fps " << fps);
    CHECK_THROWS_WITH(bad.check(), Catch::Contains("motion 'walk': frame rate") &&
                                       Catch::Contains("expected a finite number > 0"));
  }
  Motion nan_value = m;
  nan_value.values(2, 2) = std::nan("");
  CHECK_THROWS_WITH(nan_value.check(), Catch::Contains("frame 2, channel knee.Xrotation is nan"));
  Motion inf_value = m;
  inf_value.values(3, 0) = -std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(inf_value.check(), Catch::Contains("frame 3, channel hip.Yposition is -inf"));
  Motion empty{s, FrameMatrix::Zero(0, 3), 30.0, "empty"};
  CHECK_NOTHROW(empty.check());
  CHECK(empty.duration() == 0);
}
