// trim (ImportOptions, every importer): calibration frames found on the clips of ../shared/data
// that have them and on none of the others; a rest pose prepended to every clip (what Daz and
// iClone exports do) is dropped and leaves the clip read as before, also written in other units,
// at a lying frame rate or with a glitch later on; explicit ranges and bad values.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/motion/calibration.hpp"
#include "test_bvh_data.hpp"

using kg::io::ImportedMotion;
using kg::io::ImportOptions;

namespace {

std::string all(const std::vector<std::string>& notes) {
  std::string s;
  for (const std::string& n : notes) s += n + "\n";
  return s;
}

bool contains(const std::vector<std::string>& notes, const std::string& part) {
  return all(notes).find(part) != std::string::npos;
}

// Files whose first frames are an exporter's calibration pose (SOURCES.md: cgspeed's Daz files
// prepend a synthetic T-pose; the iClone 007_05 export starts in the rig's pose; the CMU take
// 16_15 starts with the left arm's "0 0 0" placeholder, in MotionBuilder's BVH too).
bool starts_calibrated(const std::string& path) {
  return path.find("bvh_daz") != std::string::npos || path.find("007_05") != std::string::npos ||
         path.find("16_15") != std::string::npos;
}

// The clip with the skeleton's rest pose (every rotation 0, position channels as in frame 0)
// put before its frame 0, in file units.
kg::motion::Motion with_rest_pose_first(const kg::motion::Motion& m) {
  kg::motion::Motion out = m;
  out.values.resize(m.frame_count() + 1, m.values.cols());
  out.values.bottomRows(m.frame_count()) = m.values;
  out.values.row(0) = m.values.row(0);
  const kg::motion::Skeleton& s = *m.skeleton;
  for (int j = 0; j < s.joint_count(); ++j)
    for (std::size_t c = 0; c < s.joint(j).channels.size(); ++c)
      if (kg::motion::is_rotation(s.joint(j).channels[c].kind))
        out.values(0, s.joint(j).first_channel + static_cast<int>(c)) = 0;
  return out;
}

}  // namespace

TEST_CASE("trim auto: calibration frames on the clips that start with them, none on the others") {
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) continue;
    ++seen;
    const ImportedMotion in = kg::io::import_bvh(*path, {});
    const int dropped = f.frames - in.motion.frame_count();
    INFO(f.path << "\n" << all(in.notes));
    CHECK(contains(in.notes, "trim auto: "));
    if (starts_calibrated(f.path)) {
      CHECK(dropped >= 1);
      CHECK(dropped / in.motion.fps <= 0.05);  // a pose and a blend out of it, not the motion
      CHECK(contains(in.notes, " calibration: "));
      CHECK(contains(in.notes, "dropped (trim: none keeps them)"));
    } else {
      CHECK(dropped == 0);
      CHECK(contains(in.notes, "no calibration frames"));
    }
    const ImportedMotion none = kg::io::import_bvh(*path, {.trim = "none"});
    CHECK(none.motion.frame_count() == f.frames);
    CHECK_FALSE(contains(none.notes, "trim"));
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("trim auto: a rest pose put first is dropped, the clip read as before") {
  // Each real clip with its skeleton's rest pose as a new frame 0, in its own units, in mm, at
  // twice and half its rate: the same frames kept (one more dropped), the same values.
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) continue;
    ++seen;
    INFO(f.path);
    const kg::io::BvhClip clip = kg::io::read_bvh(*path);
    const kg::test::TempDir dir;
    const auto plain = dir.write("plain.bvh", kg::io::write_bvh_string(clip.motion, {.precision = 9}));
    const kg::motion::Motion posed = with_rest_pose_first(clip.motion);
    const auto first = dir.write("rest_first.bvh", kg::io::write_bvh_string(posed, {.precision = 9}));
    // In metres, +Y up (all of these files are Y up), written in mm.
    const kg::motion::Motion posed_metres =
        with_rest_pose_first(kg::io::import_bvh(*path, {.trim = "none"}).motion);
    const auto in_mm = dir.write("rest_first_mm.bvh",
                                 kg::io::write_bvh_string(posed_metres, {.units = "mm", .precision = 9}));
    for (double rate_factor : {1.0, 2.0, 0.5}) {
      INFO("rate x" << rate_factor);
      const ImportOptions options{.fps = clip.motion.fps * rate_factor};
      const ImportedMotion before = kg::io::import_bvh(plain, options);
      const ImportedMotion after = kg::io::import_bvh(first, options);
      INFO(all(before.notes) << all(after.notes));
      CHECK(contains(after.notes, " calibration: "));
      REQUIRE(after.motion.frame_count() == before.motion.frame_count());
      CHECK(after.motion.values == before.motion.values);
      const ImportedMotion mm = kg::io::import_bvh(in_mm, options);
      CHECK(kg::io::unit_name(mm.motion.skeleton->source_unit_metres) == "mm");
      REQUIRE(mm.motion.frame_count() == before.motion.frame_count());
      CHECK((mm.motion.values - before.motion.values).cwiseAbs().maxCoeff() < 1e-9);
    }
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("trim auto: a clip that moves, then jumps to its rest pose, keeps every frame") {
  // A glitch is no calibration pose: the frames before it do not hold one pose.
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path || starts_calibrated(f.path) || f.frames < 40) continue;
    ++seen;
    INFO(f.path);
    kg::motion::Motion m = kg::io::import_bvh(*path, {.trim = "none"}).motion;
    const kg::motion::Motion rest = with_rest_pose_first(m);
    const int glitch = m.frame_count() / 3;
    m.values.row(glitch) = rest.values.row(0);
    m.values.row(glitch).head(3) = m.values.row(glitch - 1).head(3);
    const kg::motion::CalibrationCut cut = kg::motion::detect_calibration_frames(m);
    INFO(cut.evidence);
    CHECK(cut.frames == 0);
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("trim FIRST..LAST keeps those frames, bad values are refused with the range") {
  auto path = kg::test::data_file("other_skeletons/games105/walk60.bvh");
  if (!path) {
    WARN("skipped: other_skeletons/games105/walk60.bvh not found");
    return;
  }
  const ImportedMotion all_frames = kg::io::import_bvh(*path, {.trim = "none"});
  const int n = all_frames.motion.frame_count();
  const ImportedMotion some = kg::io::import_bvh(*path, {.trim = "10..19"});
  REQUIRE(some.motion.frame_count() == 10);
  CHECK(some.motion.values == all_frames.motion.values.middleRows(10, 10));
  CHECK(contains(some.notes, "trim 10..19: frames 10..19 kept of 0.." + std::to_string(n - 1)));
  const ImportedMotion tail = kg::io::import_bvh(*path, {.trim = "5.."});
  CHECK(tail.motion.frame_count() == n - 5);
  CHECK(kg::io::import_bvh(*path, {.trim = "0.." + std::to_string(n - 1)}).motion.values ==
        all_frames.motion.values);

  for (const char* bad : {"", "10", "..5", "5..3", "-1..4", "a..b", "1..2..3", "99999999999..", " 1..2"}) {
    INFO("trim '" << bad << "'");
    const ImportOptions o{.trim = bad};
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("ImportOptions.trim") &&
                                        Catch::Contains("auto, none, FIRST..LAST or FIRST.."));
  }
  CHECK_THROWS_WITH(
      kg::io::import_bvh(*path, {.trim = "0.." + std::to_string(n)}),
      Catch::Contains("the clip has " + std::to_string(n) + " frames (0.." + std::to_string(n - 1) + ")"));
}
