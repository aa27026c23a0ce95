// Import options (units, up, fps) applied to BVH clips: what auto picks on every real file and
// says so, Z-up handling, scaling of everything that is a length, fps overrides.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/nodes.hpp"
#include "kg/motion/kinematics.hpp"
#include "test_bvh_data.hpp"

using kg::io::apply_import_options;
using kg::io::ImportOptions;
using kg::io::parse_bvh;
using kg::motion::ChannelKind;

namespace {

bool contains(const std::vector<std::string>& notes, const std::string& part) {
  for (const std::string& n : notes)
    if (n.find(part) != std::string::npos) return true;
  return false;
}

std::string all(const std::vector<std::string>& notes) {
  std::string s;
  for (const std::string& n : notes) s += n + "\n";
  return s;
}

// World positions (metres, +Y up) of joints and End Sites in one frame.
std::vector<Eigen::Vector3d> world_points(const kg::motion::Motion& m, int frame) {
  const auto& s = *m.skeleton;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  kg::motion::forward_kinematics(s, m.values.row(frame), world);
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < s.joint_count(); ++j) {
    points.push_back(world[j].translation());
    for (const auto& tip : s.joint(j).end_sites) points.push_back(world[j] * tip);
  }
  return points;
}

double extent_y(const std::vector<Eigen::Vector3d>& points) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& p : points) lo = std::min(lo, p.y()), hi = std::max(hi, p.y());
  return hi - lo;
}

// A 1.75 m figure standing along +Z in cm: legs down -Z, spine up +Z, arms along X.
const char* kZUp =
    "HIERARCHY\n"
    "ROOT pelvis\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"
    " JOINT thigh\n {\n  OFFSET 10 0 -5\n  CHANNELS 3 Zrotation Yrotation Xrotation\n"
    "  JOINT shin\n  {\n   OFFSET 0 0 -45\n   CHANNELS 3 Zrotation Yrotation Xrotation\n"
    "   End Site\n   {\n    OFFSET 0 -8 -45\n   }\n  }\n }\n"
    " JOINT chest\n {\n  OFFSET 0 0 50\n  CHANNELS 3 Zrotation Yrotation Xrotation\n"
    "  JOINT arm\n  {\n   OFFSET 20 0 0\n   CHANNELS 3 Zrotation Yrotation Xrotation\n"
    "   End Site\n   {\n    OFFSET 50 0 0\n   }\n  }\n"
    "  End Site\n  {\n   OFFSET 0 0 30\n  }\n }\n}\n"
    "MOTION\nFrames: 2\nFrame Time: 0.01\n"
    "5 20 95 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n"
    "6 20 95 10 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n";

}  // namespace

TEST_CASE("import options: unit factors, names, params") {
  CHECK(kg::io::metres_per_unit("m") == 1.0);
  CHECK(kg::io::metres_per_unit("cm") == 0.01);
  CHECK(kg::io::metres_per_unit("mm") == 0.001);
  CHECK(kg::io::metres_per_unit("inch") == 0.0254);
  CHECK(kg::io::metres_per_unit("asf") == Approx(0.0564444444).epsilon(1e-9));
  CHECK_THROWS_AS(kg::io::metres_per_unit("auto"), std::invalid_argument);
  CHECK_THROWS_AS(kg::io::metres_per_unit("feet"), std::invalid_argument);
  CHECK(kg::io::unit_name(0.01) == "cm");
  CHECK(kg::io::unit_name(0.0254 / 0.45) == "asf");
  CHECK(kg::io::unit_name(1.0 / 128) == "0.0078125 m");

  auto params = kg::io::import_option_params("asf");
  REQUIRE(params.size() == 4);
  CHECK(params[0].name == "units");
  CHECK(params[0].type == kg::graph::ParamType::Enum);
  CHECK(std::get<std::string>(params[0].default_value) == "asf");
  CHECK(params[0].choices == std::vector<std::string>{"auto", "m", "cm", "mm", "inch", "asf"});
  CHECK(params[1].name == "up");
  CHECK(params[1].choices == std::vector<std::string>{"auto", "y", "z"});
  CHECK(params[2].name == "fps");
  CHECK(params[2].type == kg::graph::ParamType::String);  // a rate, 0 or auto
  CHECK(std::get<std::string>(params[2].default_value) == "0");
  CHECK(params[3].name == "trim");
  CHECK(std::get<std::string>(params[3].default_value) == "auto");
  CHECK_THROWS_AS(kg::io::import_option_params("furlong"), std::invalid_argument);

  kg::graph::Params p({{"units", std::string("cm")},
                       {"up", std::string("z")},
                       {"fps", std::string("120")},
                       {"trim", std::string("3..")}});
  ImportOptions o = kg::io::import_options_from(p);
  CHECK(o.units == "cm");
  CHECK(o.up == "z");
  CHECK(o.fps == 120.0);
  CHECK_FALSE(o.fps_from_flights);
  CHECK(o.trim == "3..");
  kg::graph::Params automatic({{"units", std::string("auto")},
                               {"up", std::string("auto")},
                               {"fps", std::string("auto")},
                               {"trim", std::string("auto")}});
  CHECK(kg::io::import_options_from(automatic).fps_from_flights);
  CHECK(kg::io::import_options_from(automatic).fps == 0);
  for (const char* bad : {"-1", "fast", "inf"}) {
    kg::graph::Params wrong({{"units", std::string("auto")},
                             {"up", std::string("auto")},
                             {"fps", std::string(bad)},
                             {"trim", std::string("auto")}});
    CHECK_THROWS_WITH(kg::io::import_options_from(wrong), Catch::Contains(bad) && Catch::Contains("auto"));
  }
}

TEST_CASE("import options: bad options are refused") {
  auto clip = parse_bvh(kZUp, "z.bvh");
  kg::motion::Motion m = clip.motion;
  CHECK_THROWS_AS(apply_import_options(m, {.units = "yards"}, 100, "z.bvh"), std::invalid_argument);
  CHECK_THROWS_AS(apply_import_options(m, {.up = "x"}, 100, "z.bvh"), std::invalid_argument);
  CHECK_THROWS_AS(apply_import_options(m, {.fps = -1}, 100, "z.bvh"), std::invalid_argument);
  CHECK_THROWS_AS(apply_import_options(m, {.fps = 0}, 0, "z.bvh"), std::invalid_argument);
  CHECK_NOTHROW(apply_import_options(m, {.fps = 60}, 0, "z.bvh"));
}

TEST_CASE("import options: a Z-up file is found Z-up, turned +Y up, and said so") {
  auto clip = parse_bvh(kZUp, "z.bvh");
  kg::motion::Motion m = clip.motion;
  auto notes = apply_import_options(m, {}, 1.0 / clip.frame_time, "z.bvh");
  INFO(all(notes));
  CHECK(kg::io::up_axis_name(m.skeleton->file_to_world) == "z");
  CHECK(contains(notes, "z.bvh: up auto: the median of 2 frames spans 13.15 along Y and 175 along Z"));
  CHECK(contains(notes, "taken as Z up"));
  CHECK(contains(notes, "z.bvh: units auto: standing height 175 file units, taken as cm (1.75 m)"));
  CHECK(m.skeleton->source_unit_metres == 0.01);
  // +Z of the file is +Y of the world; the frame is right-handed: file +Y goes to world -Z.
  const Eigen::Matrix3d& r = m.skeleton->file_to_world;
  CHECK((r * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY()));
  CHECK((r * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));
  CHECK(r.determinant() == Approx(1.0));
  auto points = world_points(m, 0);
  CHECK(extent_y(points) == Approx(1.75));
  CHECK(points[0].isApprox(Eigen::Vector3d(0.05, 0.95, -0.20)));  // root (5, 20, 95) cm in the file
  // Channels stay in file coordinates: only lengths were scaled.
  CHECK(m.values(0, 2) == Approx(0.95));
  CHECK(m.values(1, 3) == Approx(10 * std::numbers::pi / 180));

  // up: y keeps the file's axes, and with them a lying figure.
  kg::motion::Motion as_y = clip.motion;
  auto notes_y = apply_import_options(as_y, {.units = "cm", .up = "y"}, 100, "z.bvh");
  CHECK(kg::io::up_axis_name(as_y.skeleton->file_to_world) == "y");
  CHECK(contains(notes_y, "not a human height"));  // 0.08 m along Y
}

TEST_CASE("import options: lengths, End Sites, position values and limits scale, angles do not") {
  kg::motion::Skeleton s;
  kg::motion::Joint root;
  root.name = "root";
  root.offset = Eigen::Vector3d(1, 2, 3);
  root.channels = {{kg::motion::ChannelKind::Yposition, -10, 200},
                   {kg::motion::ChannelKind::Zrotation, -1, 1}};
  root.end_sites = {{0, 170, 0}};
  s.add_joint(root);
  kg::motion::Motion m;
  m.skeleton = std::make_shared<const kg::motion::Skeleton>(s);
  m.values.resize(1, 2);
  m.values << 100, 0.5;
  const auto original = m.skeleton;
  auto notes = apply_import_options(m, {.units = "auto", .up = "y"}, 30, "limits.bvh");
  INFO(all(notes));
  CHECK(contains(notes, "limits.bvh: units auto: standing height 170 file units, taken as cm (1.70 m)"));
  CHECK(original->joint(0).offset.x() == 1.0);  // the shared skeleton is not touched
  const auto& j = m.skeleton->joint(0);
  CHECK(j.offset.isApprox(Eigen::Vector3d(0.01, 0.02, 0.03)));
  CHECK(j.end_sites[0].isApprox(Eigen::Vector3d(0, 1.7, 0)));
  CHECK(j.channels[0].min == Approx(-0.1));
  CHECK(j.channels[0].max == Approx(2.0));
  CHECK(j.channels[1].min == -1.0);
  CHECK(j.channels[1].max == 1.0);
  CHECK(m.values(0, 0) == Approx(1.0));
  CHECK(m.values(0, 1) == 0.5);
  CHECK(m.fps == 30.0);

  // A unit the file declares wins over the guess.
  kg::motion::Motion d;
  d.skeleton = original;
  d.values = m.values;
  d.values(0, 0) = 100;
  auto declared = apply_import_options(d, {.units = "auto", .up = "y"}, 30, "x.asf", 0.0254 / 0.45);
  INFO(all(declared));
  CHECK(d.skeleton->source_unit_metres == Approx(0.0254 / 0.45));
  CHECK(contains(declared, "x.asf: units auto: the file declares asf"));
}

TEST_CASE("import options: units auto on every BVH of ../shared/data, said in a note") {
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) {
      WARN("skipped: " << f.path << " not found");
      continue;
    }
    ++seen;
    kg::io::ImportedMotion in = kg::io::import_bvh(*path, {});
    INFO(f.path << "\n" << all(in.notes));
    const auto& s = *in.motion.skeleton;
    CHECK(kg::io::unit_name(s.source_unit_metres) == f.units);
    CHECK(contains(in.notes, std::string("taken as ") + f.units + " ("));
    CHECK(contains(in.notes, "taken as Y up"));
    CHECK(kg::io::up_axis_name(s.file_to_world) == "y");
    // The rate the header's printed digits stand for (0.008333 is 1/120 s), said when it is not
    // 1/Frame Time itself.
    CHECK(in.motion.fps == Approx(1.0 / f.frame_time).epsilon(1e-4));
    CHECK(contains(in.notes, "s to its printed digits (1/Frame Time = ") ==
          (in.motion.fps != 1.0 / f.frame_time));
    CHECK(in.file_frame_time == f.frame_time);
    // A standing human once in metres (the salsa files are the 1.53 m Daz figure shrunk 128
    // times: taken as m, 1.19 m).
    const double h = extent_y(world_points(in.motion, 0));
    if (std::string(f.path).find("_scaled") != std::string::npos)
      CHECK(h == Approx(1.19).margin(0.05));
    else
      CHECK((h > 1.3 && h < 2.1));
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("import options: 16_15.bvh's root stands at 0.97 m, not the doubled 1.95 m") {
  auto path = kg::test::data_file("cmu/bvh_motionbuilder/16_15.bvh");
  if (!path) {
    WARN("skipped: cmu/bvh_motionbuilder/16_15.bvh not found");
    return;
  }
  kg::io::ImportedMotion in = kg::io::import_bvh(*path, {.trim = "none"});
  auto points = world_points(in.motion, 0);
  CHECK(points[0].y() == Approx(0.97422).margin(1e-9));
  CHECK(points[0].x() == Approx(0.06939).margin(1e-9));
}

TEST_CASE("import options: Bandai files (6 channels per joint) stand at a human height") {
  for (const char* rel : {"other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh",
                          "other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh"}) {
    auto path = kg::test::data_file(rel);
    if (!path) {
      WARN("skipped: " << rel << " not found");
      continue;
    }
    INFO(rel);
    kg::io::ImportedMotion in = kg::io::import_bvh(*path, {.units = "cm"});
    const auto& s = *in.motion.skeleton;
    for (const auto& j : s.joints()) CHECK(j.channels.size() == 6);
    const int hips = s.find_joint("Hips"), head = s.find_joint("Head");
    REQUIRE(hips >= 0);
    REQUIRE(head >= 0);
    for (int f = 0; f < in.motion.frame_count(); ++f) {
      std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
      kg::motion::forward_kinematics(s, in.motion.values.row(f), world);
      const double hip_y = world[hips].translation().y(), head_y = world[head].translation().y();
      // Adding position channels to OFFSETs would put the hips near 1.7 m and the head above 3 m.
      CHECK((hip_y > 0.7 && hip_y < 1.1));
      CHECK((head_y > 1.1 && head_y < 1.8));  // the base of the head; the dash leans forward
    }
  }
}

TEST_CASE("import options: fps overrides a lying header (16_01.bvh is 120 fps, says 30)") {
  auto path = kg::test::data_file("cmu/bvh_cmu_names/16_01.bvh");
  if (!path) {
    WARN("skipped: cmu/bvh_cmu_names/16_01.bvh not found");
    return;
  }
  kg::io::ImportedMotion in = kg::io::import_bvh(*path, {.fps = 120});
  INFO(all(in.notes));
  CHECK(in.motion.fps == 120.0);
  CHECK(in.motion.frame_count() == 322);
  CHECK(in.motion.duration() == Approx(321.0 / 120));
  CHECK(contains(in.notes, "16_01.bvh: fps 120 from the options; the file says 30"));
  CHECK(!contains(in.notes, "printed digits"));  // the override is the one fps note
  CHECK(contains(in.notes, "taken as asf ("));
  kg::io::ImportedMotion header = kg::io::import_bvh(*path, {});
  CHECK(header.motion.fps == 30);  // "Frame Time: 0.033333"
  CHECK(contains(header.notes,
                 "16_01.bvh: fps 30: Frame Time 0.033333 s is 1/30 s to its printed digits "
                 "(1/Frame Time = 30.0003); set fps to override"));
  CHECK(!contains(header.notes, "from the options"));
}

TEST_CASE("import options: a BVH of zero frames scales its skeleton and has no values to scale") {
  // Fuzzing (issue 13): scaling the position columns of a 0-frame clip made Eigen offset the
  // row-major matrix's null data pointer (undefined behaviour under -fsanitize=undefined).
  const std::string text =
      "HIERARCHY\nROOT hip\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Xrotation Yrotation\n  End Site\n  {\n    OFFSET 0 170 0\n  }\n}\nMOTION\nFrames: 0\nFrame Time: "
      "0.0333333\n";
  auto clip = parse_bvh(text, "empty.bvh");
  REQUIRE(clip.motion.frame_count() == 0);
  kg::motion::Motion m = clip.motion;
  auto notes = apply_import_options(m, {.units = "cm", .up = "y"}, 1.0 / clip.frame_time, "empty.bvh");
  INFO(all(notes));
  CHECK(m.frame_count() == 0);
  CHECK(m.values.cols() == 6);
  CHECK(m.skeleton->joint(0).end_sites[0].isApprox(Eigen::Vector3d(0, 1.7, 0)));
  CHECK(m.fps == Approx(30.0).epsilon(1e-5));
}

TEST_CASE("import options: a static root joint above the figure changes neither up nor units") {
  // Issue 14: a walk whose root stays at the origin while its hips child carries the translation
  // (the Bandai Namco layout) was taken as Z up: the origin and the walker spanned metres along
  // the walking direction in every frame. Each real clip, given such a root and walked 4 of its
  // heights along file Z away from it, is read as before.
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) continue;
    INFO(f.path);
    const kg::io::BvhClip clip = kg::io::read_bvh(*path);
    const kg::motion::Skeleton& s = *clip.motion.skeleton;
    const auto& root_channels = s.joint(0).channels;
    const auto z = std::find_if(root_channels.begin(), root_channels.end(), [](const kg::motion::Channel& c) {
      return c.kind == ChannelKind::Zposition;
    });
    if (z == root_channels.end()) continue;
    ++seen;
    kg::motion::Skeleton t;
    t.add_joint({.name = "static_root", .parent = -1});
    for (int j = 0; j < s.joint_count(); ++j) {
      kg::motion::Joint joint = s.joint(j);
      joint.parent = joint.parent < 0 ? 0 : joint.parent + 1;
      t.add_joint(joint);
    }
    kg::motion::Motion moved = clip.motion;
    moved.skeleton = std::make_shared<const kg::motion::Skeleton>(std::move(t));
    const kg::io::ImportedMotion before = kg::io::import_bvh(*path, {});
    const double height =
        extent_y(world_points(before.motion, 0)) / before.motion.skeleton->source_unit_metres;
    const int column = static_cast<int>(z - root_channels.begin());
    for (int frame = 0; frame < moved.frame_count(); ++frame)
      moved.values(frame, column) += 4 * height * frame / std::max(1, moved.frame_count() - 1);
    const kg::test::TempDir dir;
    const auto file = dir.write("static_root.bvh", kg::io::write_bvh_string(moved, {.precision = 9}));
    const kg::io::ImportedMotion after = kg::io::import_bvh(file, {});
    INFO(all(after.notes));
    CHECK(kg::io::up_axis_name(after.motion.skeleton->file_to_world) == "y");
    CHECK(after.motion.skeleton->source_unit_metres == before.motion.skeleton->source_unit_metres);
    CHECK(contains(after.notes,
                   "without the static root joint(s) 'static_root' (at one place in every frame)"));
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("import options: a small character in cm is read as cm, not as a giant in inches") {
  // retarget.yaml's scale 0.6 made a 0.92 m figure of 09_06.bvh's Daz figure, written in cm: 91.6
  // file units, 0.92 m in cm but 2.33 m in inches, taller than any human. Each real clip, made
  // 1.0 m and 1.2 m tall (frame 0) and written in cm, is read as cm; made 0.7 m (1.8 to 2.0 m in
  // inches, a human height too, by the larger of rest pose and frame 0) it is read as inches,
  // and the note names the cm reading.
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) continue;
    INFO(f.path);
    ++seen;
    const kg::io::ImportedMotion before = kg::io::import_bvh(*path, {.trim = "none"});
    const double height = extent_y(world_points(before.motion, 0));
    for (const double target : {1.0, 1.2, 0.7}) {
      INFO("made " << target << " m tall");
      const double shrink = target / height;
      kg::motion::Skeleton small = *before.motion.skeleton;
      kg::motion::Motion shrunk = before.motion;
      for (int j = 0; j < small.joint_count(); ++j) {
        kg::motion::Joint& joint = small.joint_mut(j);
        joint.offset *= shrink;
        for (auto& e : joint.end_sites) e *= shrink;
        for (std::size_t c = 0; c < joint.channels.size(); ++c)
          if (!kg::motion::is_rotation(joint.channels[c].kind))
            shrunk.values.col(joint.first_channel + static_cast<int>(c)) *= shrink;
      }
      shrunk.skeleton = std::make_shared<const kg::motion::Skeleton>(std::move(small));
      const kg::test::TempDir dir;
      const auto file =
          dir.write("small.bvh", kg::io::write_bvh_string(shrunk, {.units = "cm", .precision = 9}));
      const kg::io::ImportedMotion after = kg::io::import_bvh(file, {.trim = "none"});
      INFO(all(after.notes));
      if (target > 2.3 / (0.0254 / 0.01)) {
        CHECK(kg::io::unit_name(after.motion.skeleton->source_unit_metres) == "cm");
        CHECK(extent_y(world_points(after.motion, 0)) == Approx(target).epsilon(1e-6));
      } else {
        CHECK(kg::io::unit_name(after.motion.skeleton->source_unit_metres) == "inch");
        CHECK(contains(after.notes, "; cm would make it 0."));
        CHECK(contains(after.notes, " m: set units=cm if it is"));
      }
    }
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}
