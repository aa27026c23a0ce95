// motion.inspect (kg/motion/inspect.hpp) on the clips of ../shared/data: the rate a flight's
// gravity implies, whatever rate the header states; calibration frames; plants and flights on
// every clip; and the node's report and figures.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/base/json.hpp"
#include "kg/base/report.hpp"
#include "kg/base/text.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/motion/inspect.hpp"
#include "test_bvh_data.hpp"

using kg::io::ImportOptions;
using kg::motion::inspect_motion;
using kg::motion::MotionInspection;

namespace {

std::optional<kg::motion::Motion> read(const std::string& relative, double fps = 0) {
  const std::filesystem::path path = std::filesystem::path(KG_DATA_DIR) / relative;
  if (!std::filesystem::exists(path)) return std::nullopt;
  return kg::io::import_bvh(path, ImportOptions{.fps = fps, .trim = "none"}).motion;
}

}  // namespace

TEST_CASE("inspect: a jump's flight gives the true rate, whatever the header says", "[io][inspect][data]") {
  // 16_01.bvh says 30 fps and is 120 (SOURCES.md): its flight falls at 0.63 m/s² at 30 fps.
  for (const double stated : {0.0, 60.0, 120.0, 240.0, 480.0}) {
    const auto clip = read("cmu/bvh_cmu_names/16_01.bvh", stated);
    if (!clip) {
      WARN("skipped: 16_01.bvh not in " KG_DATA_DIR);
      return;
    }
    const MotionInspection i = inspect_motion(*clip);
    INFO("header " << i.header_fps << " fps: " << i.rate_evidence);
    CHECK(i.header_fps == Approx(stated > 0 ? stated : 30.0));
    CHECK(i.source_fps == Approx(120.0));
    REQUIRE(!i.flights.empty());
    bool weighed = false;
    for (const auto& f : i.flights)
      if (f.gravity) {
        weighed = true;
        CHECK(*f.gravity == Approx(9.81).margin(1.2));
      }
    CHECK(weighed);
    const bool lied = i.header_fps != 120.0;
    CHECK((std::find(i.fixes.begin(), i.fixes.end(), "--set source_fps=120") != i.fixes.end()) == lied);
  }
}

TEST_CASE("inspect: calibration frames, plants and flights on every BVH clip", "[io][inspect][data]") {
  int seen = 0;
  for (const kg::test::BvhDataFile& file : kg::test::bvh_data_files()) {
    const auto clip = read(file.path);
    if (!clip) continue;
    ++seen;
    const MotionInspection i = inspect_motion(*clip);
    INFO(file.path << "\n" << kg::text::join(i.summary, "\n"));
    const std::string path = file.path;
    const bool daz = path.find("bvh_daz/") != std::string::npos;
    if (daz) CHECK(i.calibration_frames == std::vector<int>{0, 1, 2, 3, 4});
    if (path.find("007_05") != std::string::npos) CHECK(i.calibration_frames == std::vector<int>{0});
    if (path.find("games105") != std::string::npos || path.find("bandai") != std::string::npos)
      CHECK(i.calibration_frames.empty());
    // Every clip stands or walks somewhere: each foot point gets a plant, or a note says why not.
    int plants = 0;
    for (const auto& p : i.plants) plants += static_cast<int>(p.spans.size());
    CHECK((plants > 0 || !i.plant_notes.empty()));
    // The header rates of these files are right but for 16_01's.
    if (path.find("16_01") == std::string::npos) CHECK(i.source_fps == Approx(i.header_fps));
    // Jumps show Earth's gravity at their rate.
    if (path.find("13_11") != std::string::npos || path.find("13_13") != std::string::npos) {
      bool weighed = false;
      for (const auto& f : i.flights)
        if (f.gravity) {
          weighed = true;
          CHECK(*f.gravity == Approx(9.81).margin(1.2));
        }
      CHECK(weighed);
    }
    // A walk never leaves the floor.
    if (path.find("walk60") != std::string::npos) CHECK(i.flights.empty());
    CHECK(i.summary.size() >= 8);
  }
  if (seen == 0) WARN("skipped: no clip of ../shared/data found in " KG_DATA_DIR);
}

TEST_CASE("inspect: the JSON has the fields scripts read", "[io][inspect][data]") {
  const auto clip = read("cmu/bvh_daz/13_11.bvh");
  if (!clip) {
    WARN("skipped: 13_11.bvh not in " KG_DATA_DIR);
    return;
  }
  const MotionInspection i = inspect_motion(*clip);
  kg::Report report;
  {
    kg::JsonWriter w(report);
    kg::motion::write_inspection_json(w, i, "cm");
  }
  const std::string text = report.text();
  for (const char* key :
       {"\"up\": \"y\"", "\"units\": \"cm\"", "\"source_fps\": 120.0", "\"header_fps\": 120.0",
        "\"calibration_frames\": [", "\"plants\": [", "\"flights\": [", "\"gravity\": ", "\"fixes\": [",
        "\"--set trim=5..\"", "\"pops\": [", "\"penetration\": {"})
    CHECK_THAT(text, Catch::Contains(key));
  CHECK(report.strings("fixes") == std::vector<std::string>{"--set trim=5.."});
  CHECK(report.strings("summary") == i.summary);
}

TEST_CASE("inspect refuses a clip too short and bad options", "[io][inspect]") {
  kg::motion::InspectOptions bad;
  bad.pop_ratio = 0;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("pop_ratio"));
  bad = {};
  bad.min_flight_frames = 2;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("min_flight_frames"));
}

TEST_CASE(
    "inspect: runs get plants at their own speed, and an ankle rolling over its planted toe is no warning",
    "[io][inspect][data]") {
  // games105's run_forward at 60 Hz: every point's stance rolls faster than a walk's 0.15 m/s;
  // the threshold is 6% of each point's 90th-percentile speed (0.35 to 0.45 m/s there).
  const auto run = read("other_skeletons/games105/run_forward.bvh");
  if (!run) {
    WARN("skipped: run_forward.bvh not in " KG_DATA_DIR);
    return;
  }
  const MotionInspection i = inspect_motion(*run);
  INFO(kg::text::join(i.summary, "\n"));
  for (const auto& p : i.plants) CHECK(p.spans.size() >= 1);
  // The same run without the relative thresholds (of the point's own speeds, of the body's pace):
  // no plant on at least one point, and a warning.
  kg::motion::InspectOptions fixed;
  fixed.plants.speed_relative = 0;
  fixed.plants.body_relative = 0;
  const MotionInspection slow = inspect_motion(*run, fixed);
  int without = 0;
  for (const auto& p : slow.plants) without += p.spans.empty();
  CHECK(without >= 1);
  // CMU 09_06 (a run, ASF/AMC): the toes are planted; the ankles roll over them and are not
  // warned of at those steps.
  const auto amc = std::filesystem::path(KG_DATA_DIR) / "cmu/asf_amc/09_06.amc";
  if (!std::filesystem::exists(amc)) return;
  const MotionInspection cmu =
      inspect_motion(kg::io::import_motion(amc.string(), "", ImportOptions{.trim = "none"}).motion);
  INFO(kg::text::join(cmu.summary, "\n"));
  CHECK(cmu.plants[1].spans.size() >= 1);  // ltoes/end
  for (const std::string& note : cmu.plant_notes)
    CHECK(note.find("lfoot gets no plant") == std::string::npos);
}

TEST_CASE("source_fps auto: a header that lies by a whole factor is read at the rate the jump shows",
          "[io][inspect][data]") {
  // The jumps' files with their Frame Time rewritten to other whole factors of the truth (120 Hz).
  const kg::test::TempDir dir;
  for (const char* relative : {"cmu/bvh_daz/13_11.bvh", "cmu/bvh_cmu_names/16_01.bvh"}) {
    const std::filesystem::path path = std::filesystem::path(KG_DATA_DIR) / relative;
    if (!std::filesystem::exists(path)) {
      WARN("skipped: " << relative << " not in " KG_DATA_DIR);
      return;
    }
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    const std::string original = text.str();
    const auto at = original.find("Frame Time:");
    REQUIRE(at != std::string::npos);
    const auto end = original.find('\n', at);
    for (const double lie : {30.0, 60.0, 120.0, 240.0}) {
      const std::filesystem::path file = dir / (std::filesystem::path(relative).stem().string() + "_" +
                                                std::to_string(static_cast<int>(lie)) + ".bvh");
      std::ofstream(file) << original.substr(0, at) << "Frame Time: " << 1.0 / lie << original.substr(end);
      const kg::io::ImportedMotion read = kg::io::import_bvh(file, ImportOptions{.fps_from_flights = true});
      INFO(relative << " stated at " << lie << " fps: " << kg::text::join(read.notes, "\n"));
      CHECK(read.motion.fps == Approx(120.0));
      // The fps override still wins, and fps 0 without auto keeps the header.
      CHECK(kg::io::import_bvh(file, ImportOptions{.fps = 50}).motion.fps == 50.0);
      CHECK(kg::io::import_bvh(file, ImportOptions{}).motion.fps == Approx(lie));
    }
  }
}
