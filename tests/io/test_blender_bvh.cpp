// Our exported BVH opens in Blender and poses the same: Debian's `blender -b` imports our files
// (tests/io/blender_import_bvh.py) and its pose-bone heads match our forward kinematics.
// Skips with a visible message when blender is not installed.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../support/process.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/motion/kinematics.hpp"
#include "test_bvh_data.hpp"

namespace {

namespace fs = std::filesystem;

bool have_blender() {
  return std::system("command -v blender >/dev/null 2>&1") == 0;
}

// A clip with every Euler order, position channels on a child listed after its rotations, a
// joint without channels, End Sites; random poses. Metres.
kg::motion::Motion mixed_orders_clip() {
  std::string text =
      "HIERARCHY\nROOT base\n{\n OFFSET 0.1 0.9 -0.2\n CHANNELS 6 Xposition Yposition Zposition Yrotation "
      "Xrotation Zrotation\n"
      " JOINT a\n {\n  OFFSET 0 0.2 0.05\n  CHANNELS 3 Xrotation Yrotation Zrotation\n"
      "  JOINT b\n  {\n   OFFSET 0.1 0.25 0\n   CHANNELS 3 Xrotation Zrotation Yrotation\n"
      "   JOINT c\n   {\n    OFFSET 0 0.3 0.02\n    CHANNELS 6 Zrotation Xrotation Yrotation Xposition "
      "Yposition Zposition\n"
      "    End Site\n    {\n     OFFSET 0 0.1 0\n    }\n   }\n  }\n"
      "  JOINT fixed\n  {\n   OFFSET -0.15 0.1 0\n   CHANNELS 0\n"
      "   JOINT d\n   {\n    OFFSET -0.2 0 0\n    CHANNELS 3 Yrotation Zrotation Xrotation\n"
      "    End Site\n    {\n     OFFSET -0.2 0 0.01\n    }\n   }\n  }\n }\n"
      " JOINT e\n {\n  OFFSET 0.1 -0.05 0\n  CHANNELS 3 Zrotation Yrotation Xrotation\n"
      "  JOINT f\n  {\n   OFFSET 0 -0.45 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "   End Site\n   {\n    OFFSET 0 -0.4 0.05\n   }\n  }\n }\n}\n"
      "MOTION\nFrames: 9\nFrame Time: 0.04\n";
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> angle(-120, 120), pos(-0.3, 0.3);
  for (int f = 0; f < 9; ++f) {
    std::ostringstream line;
    line.precision(10);
    for (int c = 0; c < 27; ++c) {
      const bool position = c < 3 || (c >= 15 && c < 18);  // base's 0..2, c's 15..17
      line << (c ? " " : "") << (position ? pos(rng) + (c == 1 ? 0.9 : 0.0) : angle(rng));
    }
    text += line.str() + "\n";
  }
  auto clip = kg::io::parse_bvh(text, "mixed.bvh");
  kg::io::apply_import_options(clip.motion, {.units = "m", .up = "y"}, 25, "mixed.bvh");
  return clip.motion;
}

struct BlenderPose {
  std::map<int, std::map<std::string, Eigen::Vector3d>> heads;  // frame -> bone -> Blender world
};

BlenderPose read_tsv(const fs::path& p) {
  BlenderPose pose;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    int frame;
    std::string bone;
    Eigen::Vector3d x;
    std::getline(s >> frame >> std::ws, bone, '\t');
    s >> x.x() >> x.y() >> x.z();
    if (s) pose.heads[frame][bone] = x;
  }
  return pose;
}

// Worst distance (metres) between Blender's heads (in metres per Blender unit `scale`) and ours,
// converted to Blender's axes.
double compare(const kg::motion::Motion& m, const BlenderPose& pose, int& compared, double scale = 1) {
  const auto& s = *m.skeleton;
  // Blender's importer maps BVH Y-up to its Z-up: (x, y, z) -> (x, -z, y).
  Eigen::Matrix3d to_blender;
  to_blender << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  double worst = 0;
  compared = 0;
  for (const auto& [frame, bones] : pose.heads) {
    kg::motion::forward_kinematics(s, m.values.row(frame), world);
    for (int j = 0; j < s.joint_count(); ++j) {
      auto it = bones.find(s.joint(j).name);
      if (it == bones.end()) {
        FAIL_CHECK("Blender has no bone " << s.joint(j).name);
        continue;
      }
      const Eigen::Vector3d ours = to_blender * (s.file_to_world.transpose() * world[j].translation());
      worst = std::max(worst, (ours - scale * it->second).norm());
      ++compared;
    }
  }
  return worst;
}

}  // namespace

TEST_CASE("blender: our BVH export imports in Blender with the same joint positions") {
  if (!have_blender()) {
    WARN("skipped: blender is not installed (apt-get install blender to run this test)");
    return;
  }
  const kg::test::TempDir dir;
  const fs::path script = fs::path(KG_SOURCE_DIR) / "tests/io/blender_import_bvh.py";

  std::vector<std::pair<std::string, kg::motion::Motion>> clips;
  clips.emplace_back("mixed", mixed_orders_clip());
  if (auto p = kg::test::data_file("cmu/bvh_motionbuilder/16_15.bvh")) {
    // ZXY, root OFFSET equal to frame 0: Blender must also replace, not add.
    clips.emplace_back("16_15", kg::io::import_bvh(*p, {}).motion);
  } else {
    WARN("cmu/bvh_motionbuilder/16_15.bvh not found: only the synthetic clip goes through Blender");
  }
  const auto asf = kg::test::data_file("cmu/asf_amc/16.asf"),
             amc = kg::test::data_file("cmu/asf_amc/16_15.amc");
  if (asf && amc) {
    // ASF bones (2-channel clavicles, axes): written with three rotation channels each, which
    // Blender needs (it refused 2 with KeyError: (2, 1, None)).
    clips.emplace_back("16_15_asf", kg::io::import_asf_amc(asf->string(), amc->string(), {}).motion);
  } else {
    WARN("cmu/asf_amc/16.asf or 16_15.amc not found: no ASF-sourced clip goes through Blender");
  }

  std::string command =
      "blender -b --factory-startup --python-exit-code 1 --python '" + script.string() + "' --";
  for (const auto& [name, m] : clips) {
    const fs::path bvh = dir / (name + ".bvh");
    kg::write_file_atomically(bvh,
                              [&clip = m](std::ostream& os) { kg::io::write_bvh(os, clip, {.units = "m"}); });
    command += " '" + bvh.string() + "' '" + (dir / (name + ".tsv")).string() + "'";
  }
  command += " > '" + (dir / "blender.log").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  INFO("command: " << command << "\nBlender's output:\n" << kg::test::read_file(dir / "blender.log"));
  REQUIRE(status == 0);

  for (const auto& [name, m] : clips) {
    INFO("clip " << name);
    const BlenderPose pose = read_tsv(dir / (name + ".tsv"));
    REQUIRE(pose.heads.size() == std::min<std::size_t>(5, static_cast<std::size_t>(m.frame_count())));
    int compared = 0;
    const double worst = compare(m, pose, compared);
    CHECK(compared == static_cast<int>(pose.heads.size()) * m.skeleton->joint_count());
    CHECK(worst < 1e-4);
    WARN("Blender vs Kinegraph, " << name << ": worst joint distance " << worst * 1e3 << " mm over "
                                  << compared << " joint-frames");
  }
}

TEST_CASE(
    "blender: every clip of ../shared/data converted by graphs/convert.yaml imports with our joint positions",
    "[data]") {
  if (!have_blender()) {
    WARN("skipped: blender is not installed (apt-get install blender to run this test)");
    return;
  }
  const fs::path data = fs::path(KG_SOURCE_DIR) / "../shared/data";
  std::vector<fs::path> clips;
  if (fs::exists(data))
    for (const auto& entry : fs::recursive_directory_iterator(data))
      if (entry.path().extension() == ".bvh" || entry.path().extension() == ".amc")
        clips.push_back(entry.path());
  std::sort(clips.begin(), clips.end());
  if (clips.empty()) {
    WARN("skipped: no clip in " << data.string());
    return;
  }
  const kg::test::TempDir dir;
  const fs::path script = fs::path(KG_SOURCE_DIR) / "tests/io/blender_import_bvh.py";
  std::string command =
      "blender -b --factory-startup --python-exit-code 1 --python '" + script.string() + "' --";
  std::vector<std::string> names;
  for (const fs::path& clip : clips) {
    const std::string name = clip.parent_path().filename().string() + "_" + clip.stem().string();
    const kg::test::Result r = kg::test::kinegraph(
        {"run", (fs::path(KG_SOURCE_DIR) / "graphs/convert.yaml").string(), "--set", "input=" + clip.string(),
         "--set", "output=" + (dir / (name + ".bvh")).string()});
    INFO(kg::test::show(r));
    REQUIRE(r.code == 0);
    command += " '" + (dir / (name + ".bvh")).string() + "' '" + (dir / (name + ".tsv")).string() + "'";
    names.push_back(name);
  }
  command += " > '" + (dir / "blender.log").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  INFO("command: " << command << "\nBlender's output:\n" << kg::test::read_file(dir / "blender.log"));
  REQUIRE(status == 0);

  double worst_of_all = 0;
  for (std::size_t i = 0; i < clips.size(); ++i) {
    INFO(clips[i].string());
    // The clip as convert.yaml read it (auto units and up); written in cm (output_units), which
    // Blender's importer takes as its units at global_scale 1.
    const kg::motion::Motion m = kg::io::import_motion(clips[i].string(), "", {}).motion;
    const BlenderPose pose = read_tsv(dir / (names[i] + ".tsv"));
    REQUIRE(pose.heads.size() == std::min<std::size_t>(5, static_cast<std::size_t>(m.frame_count())));
    int compared = 0;
    const double worst = compare(m, pose, compared, 0.01);
    CHECK(compared == static_cast<int>(pose.heads.size()) * m.skeleton->joint_count());
    CHECK(worst < 1e-4);  // 0.1 mm
    worst_of_all = std::max(worst_of_all, worst);
  }
  WARN("Blender vs Kinegraph over " << clips.size() << " converted clips: worst joint distance "
                                    << worst_of_all * 1e3 << " mm");
}
