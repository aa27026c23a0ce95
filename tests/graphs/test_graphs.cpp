// Every pipeline in graphs/ run end to end through the kinegraph CLI, as a user runs it:
// the demo on synthesized motion, and convert.yaml on every clip of ../shared/data, whose
// output must read back to the same frames and joint world positions as its source.
#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/process.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"

namespace {

namespace fs = std::filesystem;
using kg::test::read_file;
using kg::test::Result;
using kg::test::show;
using kg::test::TempDir;

const fs::path kSource = KG_SOURCE_DIR;
const fs::path kData = KG_DATA_DIR;

using kg::test::kinegraph;

// Every motion clip in the data folder: .bvh files, and .amc files (their .asf is guessed).
std::vector<fs::path> data_clips() {
  std::vector<fs::path> clips;
  if (!fs::exists(kData)) return clips;
  for (const auto& entry : fs::recursive_directory_iterator(kData)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".bvh" || ext == ".amc") clips.push_back(entry.path());
  }
  std::sort(clips.begin(), clips.end());
  return clips;
}

// Joint origins (metres, world) of every frame of `b`, compared with the same-named joints of
// `a`; returns the worst distance.
double worst_joint_distance(const kg::motion::Motion& a, const kg::motion::Motion& b) {
  const Eigen::MatrixXd pa = kg::motion::joint_world_positions(a);
  const Eigen::MatrixXd pb = kg::motion::joint_world_positions(b);
  double worst = 0;
  for (int jb = 0; jb < b.skeleton->joint_count(); ++jb) {
    const int ja = a.skeleton->find_joint(b.skeleton->joint(jb).name);
    REQUIRE(ja >= 0);
    worst =
        std::max(worst, (pa.middleCols(3 * ja, 3) - pb.middleCols(3 * jb, 3)).rowwise().norm().maxCoeff());
  }
  return worst;
}

}  // namespace

TEST_CASE("every graph in graphs/ validates", "[graphs]") {
  // From the project root, as the README runs them: their default inputs (graphs/ladder/...)
  // are relative to it, and validate checks that the inputs given exist.
  const fs::path before = fs::current_path();
  fs::current_path(kSource);
  struct Restore {
    fs::path dir;
    ~Restore() { fs::current_path(dir); }
  } restore{before};
  for (const auto& entry : fs::directory_iterator(kSource / "graphs")) {
    if (entry.path().extension() != ".yaml") continue;
    // Without values for its required variables, a graph is valid and names what a run needs.
    const Result bare = kinegraph({"validate", entry.path().string()});
    INFO(entry.path() << "\n" << show(bare));
    CHECK(bare.code == 0);
    std::vector<std::string> args{"validate", entry.path().string()};
    // Every required variable is a clip (input, follow, lead, ...).
    for (const auto& variable : YAML::LoadFile(entry.path().string())["variables"])
      if (variable.second["required"] && variable.second["required"].as<bool>())
        args.insert(args.end(), {"--set", variable.first.as<std::string>() + "=" +
                                              (kSource / "tests/graphs/data/two_joints.bvh").string()});
    const Result r = kinegraph(args);
    INFO(entry.path() << "\n" << show(r));
    CHECK(r.code == 0);
  }
}

TEST_CASE("graphs/demo.yaml runs on synthesized motion and writes readable clips", "[graphs]") {
  TempDir out;
  const Result r =
      kinegraph({"run", (kSource / "graphs/demo.yaml").string(), "--set", "out=" + out.path().string(),
                 "--jobs", "2", "--report", (out / "report.json").string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK(fs::exists(out / "report.json"));

  const auto walk = kg::io::read_bvh(out / "walk_120hz.bvh").motion;
  const auto walk_30 = kg::io::read_bvh(out / "walk_30hz.bvh").motion;
  const auto walk_smooth = kg::io::read_bvh(out / "walk_smooth.bvh").motion;
  const auto jump = kg::io::read_bvh(out / "jump_120hz.bvh").motion;
  const auto jump_30 = kg::io::read_bvh(out / "jump_30hz.bvh").motion;
  CHECK(walk.fps == Approx(120));
  CHECK(walk_30.fps == Approx(30));
  CHECK(walk_30.frame_count() == kg::motion::resampled_frame_count(walk.frame_count(), 120, 30));
  CHECK(jump_30.frame_count() == kg::motion::resampled_frame_count(jump.frame_count(), 120, 30));
  CHECK(walk_smooth.frame_count() == walk.frame_count());
  CHECK(walk.skeleton->joint_count() == jump.skeleton->joint_count());

  // The retargeting branch: the walk on a character of 0.6 times the size, its footplants met.
  const auto small = kg::io::read_bvh(out / "walk_small_30hz.bvh").motion;
  CHECK(small.frame_count() == walk_30.frame_count());
  CHECK(small.skeleton->rest_height() == Approx(0.6 * walk_30.skeleton->rest_height()).epsilon(1e-6));
  const YAML::Node metrics = YAML::LoadFile((out / "walk_small_metrics.json").string());
  CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
  CHECK(metrics["foot_skate_cm"]["worst"].as<double>() <= 0.2);
}

TEST_CASE("run --reproducible twice writes the same bytes: every file graphs/demo.yaml writes", "[graphs]") {
  // The retime report's message carried the solve time in ms, so two runs differed (issue 14).
  TempDir dir;
  std::map<std::string, std::string> first;
  for (const std::string run : {"a", "b"}) {
    const fs::path out = dir / run;
    const Result r = kinegraph({"run", (kSource / "graphs/demo.yaml").string(), "--set",
                                "out=" + out.string(), "--jobs", "2", "--reproducible"});
    INFO(show(r));
    REQUIRE(r.code == 0);
    int files = 0;
    for (const auto& entry : fs::directory_iterator(out)) {
      const std::string name = entry.path().filename().string(), bytes = read_file(entry.path());
      ++files;
      INFO(name);
      if (run == "a") {
        first[name] = bytes;
      } else {
        REQUIRE(first.count(name) == 1);
        CHECK(bytes == first[name]);
      }
    }
    CHECK(files == static_cast<int>(first.size()));
    CHECK(files >= 8);
  }
}

TEST_CASE("graphs/retarget.yaml retargets real walks to a smaller, a short-legged and a morphing character",
          "[graphs][data]") {
  const std::vector<fs::path> clips{kData / "cmu/bvh_motionbuilder/16_15.bvh",
                                    kData / "cmu/asf_amc/07_05.amc"};
  if (!fs::exists(clips[0]) || !fs::exists(clips[1])) {
    WARN("skipped: 16_15.bvh or 07_05.amc not found in " << kData);
    return;
  }
  TempDir out;
  for (const fs::path& clip : clips) {
    for (const std::string target :
         {"", "graphs/targets/short_legs_long_torso.yaml", "graphs/targets/morph_to_60.yaml"}) {
      const fs::path output = out / "result.bvh", report = out / "metrics.json";
      const Result r =
          kinegraph({"run", (kSource / "graphs/retarget.yaml").string(), "--set", "input=" + clip.string(),
                     "--set", "target=" + (target.empty() ? "" : (kSource / target).string()), "--set",
                     "output=" + output.string(), "--set", "report=" + report.string()});
      INFO(clip << " target " << target << "\n" << show(r));
      REQUIRE(r.code == 0);
      const kg::io::ImportedMotion source = kg::io::import_motion(clip.string(), "", {});
      const auto result = kg::io::read_bvh(output).motion;
      // Solved and written at the input's rate (fps and output_fps default to it), every frame.
      CHECK(result.fps == Approx(source.motion.fps));
      CHECK(result.frame_count() == source.motion.frame_count());
      // Equality constraints within 1 mm and no inequality violated by more (the issue's figure).
      const YAML::Node metrics = YAML::LoadFile(report.string());
      CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
      // A morphing foot shrinks under its planted ankle and toe tip (0.4 x a 12 cm foot over 4 s:
      // about 3 mm over a half-second plant), so both cannot stay put: the solve splits that.
      const bool morph = target.find("morph") != std::string::npos;
      CHECK(metrics["foot_skate_cm"]["worst"].as<double>() <= (morph ? 0.4 : 0.2));
      CHECK(metrics["solve_seconds"].as<double>() > 0);
    }
  }
}

TEST_CASE("graphs/retarget.yaml written below the input's rate: every plant checked, each its own",
          "[graphs][data]") {
  // 24 and 30 Hz divide 120; 25, 47 and 50 do not, so most frames written fall between the solve's,
  // where retarget.at_rate holds the constraints by per-frame IK. 09_06's right knee passes gimbal
  // lock in its stance, where the file switches Euler solutions (a resampling off the file's
  // solution put that toe 2.3 cm under the floor at 25 Hz).
  struct Case {
    fs::path clip;
    std::vector<int> rates;
  };
  const std::vector<Case> cases{{kData / "cmu/bvh_motionbuilder/16_15.bvh", {30, 24, 50}},
                                {kData / "cmu/bvh_daz/09_06.bvh", {25, 47}}};
  for (const Case& c : cases) {
    if (!fs::exists(c.clip)) {
      WARN("skipped: " << c.clip << " not found");
      continue;
    }
    TempDir out;
    const kg::io::ImportedMotion source = kg::io::import_motion(c.clip.string(), "", {});
    std::size_t plants_at_first_rate = 0;
    for (const int output_fps : c.rates) {
      const fs::path output = out / "result.bvh", report = out / "metrics.json";
      const Result r =
          kinegraph({"run", (kSource / "graphs/retarget.yaml").string(), "--set", "input=" + c.clip.string(),
                     "--set", "output_fps=" + std::to_string(output_fps), "--set",
                     "output=" + output.string(), "--set", "report=" + report.string()});
      INFO(c.clip.filename() << " at output_fps " << output_fps << "\n" << show(r));
      REQUIRE(r.code == 0);
      CHECK_THAT(r.err, Catch::Contains("hold: the constraints held at the rate written"));
      const auto result = kg::io::read_bvh(output).motion;
      CHECK(result.fps == Approx(output_fps));
      CHECK(std::abs(result.duration() - source.motion.duration()) <= 1.0 / output_fps + 1e-6);
      const YAML::Node metrics = YAML::LoadFile(report.string());
      CHECK(metrics["frames"].as<int>() == result.frame_count());
      CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
      CHECK(metrics["foot_skate_cm"]["worst"].as<double>() <= 0.1);
      // Plants keep their own labels at the coarse rate: none merges into the next of its foot.
      std::set<std::string> labels;
      for (const YAML::Node& plant : metrics["foot_skate_cm"]["plants"])
        labels.insert(plant["label"].as<std::string>());
      CHECK(labels.size() == metrics["foot_skate_cm"]["plants"].size());
      if (plants_at_first_rate == 0) plants_at_first_rate = labels.size();
      CHECK(labels.size() == plants_at_first_rate);
      CHECK(labels.size() >= 4);
    }
  }
}

TEST_CASE(
    "graphs/retarget.yaml on bad input: unknown joints, contradictions, other skeletons, broken targets",
    "[graphs][data]") {
  const fs::path clip = kData / "cmu/bvh_motionbuilder/16_15.bvh";
  if (!fs::exists(clip)) {
    WARN("skipped: " << clip << " not found");
    return;
  }
  TempDir work;
  auto retarget = [&](const std::vector<std::string>& sets) {
    std::vector<std::string> args{"run",   (kSource / "graphs/retarget.yaml").string(),
                                  "--set", "input=" + clip.string(),
                                  "--set", "output=" + (work / "out.bvh").string(),
                                  "--set", "report=" + (work / "metrics.json").string()};
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    return kinegraph(args);
  };

  SECTION("a constraint naming an unknown joint: file, line and the nearest name") {
    work.write("typo.yaml",
               "version: 1\nconstraints:\n  - kind: position\n    points: [{joint: lfot}]\n"
               "    params: [0, 0.1, 0]\n    frames: [10, 20]\n");
    const Result r = retarget({"constraints=" + (work / "typo.yaml").string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("typo.yaml:4") && Catch::Contains("lfot") && Catch::Contains("lfoot"));
    CHECK_FALSE(fs::exists(work / "out.bvh"));
  }

  SECTION("contradictory constraints: reported as not met; strict fails and writes nothing") {
    // The left ankle at two places 30 cm apart over the same frames.
    work.write("contradiction.yaml", R"(version: 1
constraints:
  - {kind: position, label: "ankle here", points: [{joint: lfoot}], params: [0.0, 0.1, 0.0], frames: [40, 50]}
  - {kind: position, label: "ankle there", points: [{joint: lfoot}], params: [0.3, 0.1, 0.0], frames: [40, 50]}
)");
    const Result r = retarget({"constraints=" + (work / "contradiction.yaml").string()});
    INFO(show(r));
    CHECK(r.code == 0);  // the best effort is written, and says so
    CHECK_THAT(r.err, Catch::Contains("did not converge") && Catch::Contains("ankle"));
    CHECK(fs::exists(work / "out.bvh"));
    const YAML::Node metrics = YAML::LoadFile((work / "metrics.json").string());
    CHECK(metrics["violation"]["worst_cm"].as<double>() > 10);  // 15 cm each way, at best

    fs::remove(work / "out.bvh");
    const Result strict = retarget({"constraints=" + (work / "contradiction.yaml").string(), "strict=true"});
    INFO(show(strict));
    CHECK(strict.code == 1);
    CHECK_THAT(strict.err,
               Catch::Contains("node solve (retarget.spacetime) failed") && Catch::Contains("ankle"));
    CHECK_FALSE(fs::exists(work / "out.bvh"));
  }

  SECTION("a target skeleton of another structure names the difference") {
    const fs::path other = kData / "cmu/asf_amc/07.asf";
    if (!fs::exists(other)) {
      WARN("skipped: " << other << " not found");
      return;
    }
    const Result r = retarget({"target=" + other.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("07.asf") && Catch::Contains("joint"));
    CHECK_FALSE(fs::exists(work / "out.bvh"));
  }

  SECTION("a malformed target file: file and line") {
    work.write("target.yaml", "version: 1\nbones:\n  \"lfemur\": -0.5\n");
    const Result r = retarget({"target=" + (work / "target.yaml").string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("target.yaml:3"));
    CHECK_FALSE(fs::exists(work / "out.bvh"));
  }
}

TEST_CASE("graphs/retarget.yaml on runs, a jump and a long stand of several skeletons and units",
          "[graphs][data]") {
  // CMU runs and a jump as ASF/AMC (ASF units, 120 Hz) and Daz BVH (cm), and 18 s of bending and
  // lifting on the iClone rig (cm, 60 Hz, 100 joints) whose feet stay planted for 15 s: the
  // non-skid chain must not drift over a plant that long.
  const std::vector<fs::path> clips{kData / "cmu/asf_amc/09_06.amc", kData / "cmu/bvh_daz/09_06.bvh",
                                    kData / "cmu/bvh_daz/02_03.bvh", kData / "cmu/bvh_daz/13_11.bvh",
                                    kData / "cmu/bvh_iclone_cc_rig/002_06.bvh"};
  TempDir out;
  int ran = 0;
  for (const fs::path& clip : clips) {
    if (!fs::exists(clip)) {
      WARN("skipped: " << clip << " not found");
      continue;
    }
    ++ran;
    const fs::path output = out / "result.bvh", report = out / "metrics.json";
    // strict (every foot point that touches the floor gets a plant, or a point of its foot does)
    // but on the runs: their feet roll at about 1 m/s through a stance of 0.15 to 0.25 s at
    // 120 Hz, and no threshold yet finds plants there on every point without taking a walk's
    // swing for one (issue 14, item 4, open; the run warns "gets no plant").
    const bool run = clip.stem() == "09_06" || clip.stem() == "02_03";
    const Result r =
        kinegraph({"run", (kSource / "graphs/retarget.yaml").string(), "--set", "input=" + clip.string(),
                   "--set", "scale=0.7", "--set", "output=" + output.string(), "--set",
                   "report=" + report.string(), "--set", std::string("strict=") + (run ? "false" : "true")});
    INFO(clip << "\n" << show(r));
    REQUIRE(r.code == 0);
    const YAML::Node metrics = YAML::LoadFile(report.string());
    CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
    CHECK(metrics["foot_skate_cm"]["worst"].as<double>() <= 0.2);
    CHECK(kg::io::read_bvh(output).motion.frame_count() == metrics["frames"].as<int>());
  }
  if (ran == 0) WARN("skipped: no run or jump clip in " << kData);
}

TEST_CASE("graphs/salsa.yaml retargets the follow of the salsa pair, hands held, the lead's legs kept",
          "[graphs][data]") {
  const fs::path follow = kData / "cmu/bvh_daz_two_person/61_10_scaled.bvh";
  const fs::path lead = kData / "cmu/bvh_daz_two_person/60_10_scaled.bvh";
  if (!fs::exists(follow) || !fs::exists(lead)) {
    WARN("skipped: the salsa pair is not in " << kData);
    return;
  }
  TempDir out;
  const fs::path output = out / "follow.bvh", output2 = out / "lead.bvh", report = out / "metrics.json";
  const Result r =
      kinegraph({"run", (kSource / "graphs/salsa.yaml").string(), "--set", "follow=" + follow.string(),
                 "--set", "lead=" + lead.string(), "--set", "scale=0.8", "--set", "output=" + output.string(),
                 "--set", "output2=" + output2.string(), "--set", "report=" + report.string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK(r.err.find("solve: converged") != std::string::npos);

  // The follow is 80% of her size; the lead keeps his. Every frame of both (salsa.yaml's trim:
  // none keeps the pair's frames together).
  const kg::motion::Motion follow_source =
      kg::motion::resample(kg::io::import_motion(follow.string(), "", {.trim = "none"}).motion, 30);
  const kg::motion::Motion lead_source =
      kg::motion::resample(kg::io::import_motion(lead.string(), "", {.trim = "none"}).motion, 30);
  const kg::motion::Motion small = kg::io::read_bvh(output).motion;
  const kg::motion::Motion lead_result = kg::io::read_bvh(output2).motion;
  REQUIRE(small.frame_count() == follow_source.frame_count());
  REQUIRE(lead_result.frame_count() == lead_source.frame_count());
  const int shin = small.skeleton->find_joint("lShin");
  CHECK(small.skeleton->joint(shin).offset.norm() ==
        Approx(0.8 * follow_source.skeleton->joint(shin).offset.norm()).epsilon(1e-6));

  // Hand-holds were found and hold, with every other constraint, within 1 mm.
  const YAML::Node metrics = YAML::LoadFile(report.string());
  CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
  bool held = false;
  for (const YAML::Node& k : metrics["violation"]["kinds"])
    if (k["kind"].as<std::string>() == "distance")
      held = k["rows"].as<int>() > 0 && k["violated_rows"].as<int>() == 0;
  CHECK(held);

  // The lead's lower body (frozen) is his captured one; his upper body moved to meet her.
  const std::regex fixed("hip|[lr](Buttock|Thigh|Shin|Foot)");
  double lower = 0, upper = 0;
  for (int j = 0; j < lead_source.skeleton->joint_count(); ++j) {
    const kg::motion::Joint& joint = lead_source.skeleton->joint(j);
    for (std::size_t k = 0; k < joint.channels.size(); ++k) {
      const int c = joint.first_channel + static_cast<int>(k);
      const double change = (lead_result.values.col(c) - lead_source.values.col(c)).cwiseAbs().maxCoeff();
      (std::regex_match(joint.name, fixed) ? lower : upper) =
          std::max(std::regex_match(joint.name, fixed) ? lower : upper, change);
    }
  }
  CHECK(lower < 1e-4);  // the BVH's 6 decimals
  CHECK(upper > 1e-3);
}

TEST_CASE("graphs/convert.yaml converts every clip in ../shared/data", "[graphs][data]") {
  const std::vector<fs::path> clips = data_clips();
  if (clips.empty()) {
    WARN("skipped: no motion clips found in " << kData);
    return;
  }
  TempDir out;
  for (const fs::path& clip : clips) {
    const fs::path output =
        out / (clip.stem().string() + "_" + clip.parent_path().filename().string() + ".bvh");
    const Result r = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                                "input=" + clip.string(), "--set", "output=" + output.string()});
    INFO(clip << "\n" << show(r));
    REQUIRE(r.code == 0);

    // The source as the graph read it (auto units, up and rate: 16_01.bvh is read at the 120 fps
    // its jump shows), and the output read back in cm (output_units' default) and the same up
    // axis: the same clip, to the printed precision of the export.
    const kg::io::ImportedMotion source =
        kg::io::import_motion(clip.string(), "", {.fps_from_flights = true});
    if (clip.stem() == "16_01") CHECK(source.motion.fps == 120.0);
    const auto& skeleton = *source.motion.skeleton;
    kg::io::ImportOptions same{.units = "cm", .up = kg::io::up_axis_name(skeleton.file_to_world)};
    const kg::motion::Motion back = kg::io::import_bvh(output, same).motion;
    CHECK(back.frame_count() == source.motion.frame_count());
    CHECK(back.fps == Approx(source.motion.fps).epsilon(1e-8));
    CHECK(worst_joint_distance(source.motion, back) < 1e-4);
  }
}

TEST_CASE("graphs/convert.yaml resamples and overrides fps and units", "[graphs][data]") {
  const fs::path jump = kData / "cmu/bvh_cmu_names/16_01.bvh";
  if (!fs::exists(jump)) {
    WARN("skipped: " << jump << " not found");
    return;
  }
  TempDir out;
  // 16_01.bvh says 30 fps but is 120 fps; ASF units (inches / 0.45).
  const Result r = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                              "input=" + jump.string(), "--set", "output=" + (out / "jump.bvh").string(),
                              "--set", "source_fps=120", "--set", "units=asf", "--set", "output_fps=30"});
  INFO(show(r));
  REQUIRE(r.code == 0);
  // The former names (fps, resample) give the same bytes.
  const Result former =
      kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set", "input=" + jump.string(),
                 "--set", "output=" + (out / "former.bvh").string(), "--set", "fps=120", "--set", "units=asf",
                 "--set", "resample=30"});
  INFO(show(former));
  REQUIRE(former.code == 0);
  CHECK(read_file(out / "former.bvh") == read_file(out / "jump.bvh"));
  const auto source = kg::io::read_bvh(jump).motion;
  const auto converted = kg::io::read_bvh(out / "jump.bvh").motion;
  CHECK(converted.fps == Approx(30));
  CHECK(converted.frame_count() == kg::motion::resampled_frame_count(source.frame_count(), 120, 30));
}

TEST_CASE("graphs/convert.yaml resampling a clip to its own rate keeps every frame", "[graphs]") {
  // A header's "Frame Time: 0.0333333" is 30 fps to its digits, not 30.00003: resampled to 30 the
  // clip kept 299 of 300 frames (issue 14). Its frames are those of the source, bit for bit.
  TempDir dir;
  std::string clip = kg::test::read_file(kSource / "tests/graphs/data/two_joints.bvh");
  const std::size_t frames_at = clip.find("Frames: 3");
  REQUIRE(frames_at != std::string::npos);
  std::string lines;
  for (int f = 0; f < 300; ++f)
    lines += std::to_string(0.01 * f) + " 90 0 0 0 0 0 " + std::to_string(f % 90) + " 0\n";
  clip = clip.substr(0, frames_at) + "Frames: 300\nFrame Time: 0.0333333\n" + lines;
  const fs::path input = dir.write("clip.bvh", clip), output = dir / "out.bvh";
  const Result r = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                              "input=" + input.string(), "--set", "output=" + output.string(), "--set",
                              "output_fps=30", "--set", "output_units=source"});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK(r.err.find("Frame Time 0.0333333 s is 1/30 s to its printed digits") != std::string::npos);
  const auto source = kg::io::read_bvh(input).motion;
  const auto converted = kg::io::read_bvh(output).motion;
  CHECK(source.fps == 30);
  CHECK(converted.fps == 30);
  REQUIRE(converted.frame_count() == 300);
  CHECK(worst_joint_distance(source, converted) < 1e-6);
}

TEST_CASE("graphs/convert.yaml never overwrites its input and refuses a malformed clip", "[graphs]") {
  // The input is never overwritten: an output path equal to the input is refused before running.
  TempDir work;
  fs::copy_file(kSource / "tests/graphs/data/two_joints.bvh", work / "clip.bvh");
  const std::string before = kg::test::read_file(work / "clip.bvh");
  const Result same =
      kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                 "input=" + (work / "clip.bvh").string(), "--set", "output=" + (work / "clip.bvh").string()});
  CHECK(same.code == 3);
  CHECK(kg::test::read_file(work / "clip.bvh") == before);

  // A malformed clip fails its node with file:line, exit 1, and writes nothing.
  work.write("broken.bvh", "HIERARCHY\nROOT hip\n{\n  OFFSET 0 0\n");
  const Result broken = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                                   "input=" + (work / "broken.bvh").string(), "--set",
                                   "output=" + (work / "never.bvh").string()});
  INFO(show(broken));
  CHECK(broken.code == 1);
  CHECK_THAT(broken.err, Catch::Contains("broken.bvh:4"));
  CHECK_FALSE(fs::exists(work / "never.bvh"));

  // A missing .amc in a missing folder is a missing .amc, not a skeleton that cannot be guessed.
  const fs::path missing = work / "no_such_folder/16_15.amc";
  const Result absent =
      kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set", "input=" + missing.string(),
                 "--set", "output=" + (work / "never.bvh").string()});
  INFO(show(absent));
  CHECK(absent.code == 1);
  CHECK_THAT(absent.err, Catch::Contains(missing.string() + ": no such AMC file"));
  CHECK_THAT(absent.err, !Catch::Contains("skeleton"));
  CHECK_FALSE(fs::exists(work / "never.bvh"));
}

TEST_CASE("graphs/convert.yaml refuses at load an extension no motion format claims", "[graphs]") {
  TempDir work;
  fs::copy_file(kSource / "tests/graphs/data/two_joints.bvh", work / "clip.bvh");
  const std::string readers =
                        "readers: .amc (ASF/AMC, skeleton .asf), .asf (ASF skeleton), .bvh (BVH), .csv "
                        "(robot CSV, skeleton "
                        ".urdf), .urdf (URDF)",
                    writers = "writers: .bvh (BVH), .csv (robot CSV), .json (robot JSON)";
  // Writing .fbx: no writer claims it (it used to get BVH text). Invalid graph, nothing written.
  const fs::path fbx = work / "x.fbx";
  Result r = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                        "input=" + (work / "clip.bvh").string(), "--set", "output=" + fbx.string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Catch::Contains("convert.yaml:") &&
                        Catch::Contains("node 'write' (io.export_motion): " + fbx.string() +
                                        ": no motion writer claims '.fbx'; " + writers + "; " + readers));
  CHECK_FALSE(fs::exists(fbx));
  // The extension in any case picks BVH.
  r = kinegraph({"run", (kSource / "graphs/convert.yaml").string(), "--set",
                 "input=" + (work / "clip.bvh").string(), "--set",
                 "output=" + (work / "UPPER.BVH").string()});
  INFO(show(r));
  CHECK(r.code == 0);
  CHECK(kg::test::read_file(work / "UPPER.BVH").rfind("HIERARCHY\n", 0) == 0);
  // Reading .c3d: the same, naming the readers first; `validate` says so too.
  work.write("clip.c3d", "not a motion");
  for (const char* verb : {"run", "validate"}) {
    r = kinegraph({verb, (kSource / "graphs/convert.yaml").string(), "--set",
                   "input=" + (work / "clip.c3d").string(), "--set",
                   "output=" + (work / "c3d.bvh").string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Catch::Contains("node 'source' (io.import_motion): " + (work / "clip.c3d").string() +
                                      ": no motion reader claims '.c3d'; " + readers + "; " + writers));
  }
  CHECK_FALSE(fs::exists(work / "c3d.bvh"));
}

TEST_CASE("no run overwrites a file it read: a guessed skeleton, the graph itself, the report", "[graphs]") {
  const fs::path asf = kData / "cmu/asf_amc/16.asf", amc = kData / "cmu/asf_amc/16_15.amc";
  TempDir work;
  fs::copy_file(kSource / "graphs/convert.yaml", work / "convert.yaml");
  fs::copy_file(kSource / "tests/graphs/data/two_joints.bvh", work / "clip.bvh");
  // convert.yaml's io.export_motion refuses .yaml and .asf outputs at load (no writer claims
  // them); io.export_bvh writes BVH under any name, so the run itself must refuse.
  work.write("export_bvh.yaml",
             "version: 1\nvariables:\n  input: {required: true}\n  output: {required: true}\nnodes:\n"
             "  source: {type: io.import_motion, params: {path: \"${input}\"}}\n"
             "  write: {type: io.export_bvh, params: {path: \"${output}\"}}\n"
             "connections:\n  - {from: source.motion, to: write.motion}\n");
  const std::string graph_before = kg::test::read_file(work / "convert.yaml");
  const std::string clip_before = kg::test::read_file(work / "clip.bvh");

  // The graph file as the output: refused at load by convert.yaml, by the export of the other;
  // the graph is intact.
  Result r =
      kinegraph({"run", (work / "convert.yaml").string(), "--set", "input=" + (work / "clip.bvh").string(),
                 "--set", "output=" + (work / "convert.yaml").string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Catch::Contains("no motion writer claims '.yaml'"));
  CHECK(kg::test::read_file(work / "convert.yaml") == graph_before);
  const std::string other_before = kg::test::read_file(work / "export_bvh.yaml");
  r = kinegraph({"run", (work / "export_bvh.yaml").string(), "--set", "input=" + (work / "clip.bvh").string(),
                 "--set", "output=" + (work / "export_bvh.yaml").string()});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("never overwritten"));
  CHECK(kg::test::read_file(work / "export_bvh.yaml") == other_before);

  // The run's report written over its input clip is refused; the clip is intact.
  r = kinegraph({"run", (work / "convert.yaml").string(), "--set", "input=" + (work / "clip.bvh").string(),
                 "--set", "output=" + (work / "out.bvh").string(), "--report", (work / "clip.bvh").string()});
  INFO(show(r));
  CHECK(r.code != 0);
  CHECK(kg::test::read_file(work / "clip.bvh") == clip_before);

  // An .amc whose skeleton is found by its name: the .asf is an input too.
  if (!fs::exists(asf) || !fs::exists(amc)) {
    WARN("skipped: the guessed-skeleton case needs " << asf << " and " << amc);
    return;
  }
  fs::copy_file(asf, work / "16.asf");
  fs::copy_file(amc, work / "16_15.amc");
  const std::string asf_before = kg::test::read_file(work / "16.asf");
  r = kinegraph({"run", (work / "convert.yaml").string(), "--set", "input=" + (work / "16_15.amc").string(),
                 "--set", "output=" + (work / "16.asf").string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK(kg::test::read_file(work / "16.asf") == asf_before);
  r = kinegraph({"run", (work / "export_bvh.yaml").string(), "--set",
                 "input=" + (work / "16_15.amc").string(), "--set", "output=" + (work / "16.asf").string()});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("never overwritten"));
  CHECK(kg::test::read_file(work / "16.asf") == asf_before);
}

TEST_CASE(
    "every graph that reads a clip takes units, up, source_fps, trim, fps, output_fps and output_units, "
    "wired to "
    "its nodes",
    "[graphs]") {
  // One vocabulary (issue 14): each name reaches a node param, so a bad value fails validation
  // at that param; a graph that declared a name and ignored it would say "valid".
  const fs::path clip = kSource / "tests/graphs/data/two_joints.bvh";
  int checked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kSource / "graphs")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string text = read_file(entry.path());
    if (text.find("\nnodes:") == std::string::npos || text.find("\n  input:") == std::string::npos) continue;
    INFO(entry.path().string());
    ++checked;
    std::vector<std::string> base{"validate", entry.path().string(), "--set", "input=" + clip.string()};
    if (text.find("\n  pin_source:") != std::string::npos)
      for (const char* pin : {"pin_source=0.1", "pin_output=0.1"}) base.insert(base.end(), {"--set", pin});
    const Result valid = kinegraph(base);
    INFO(show(valid));
    CHECK(valid.code == 0);
    for (const auto& [name, bad, expected] : std::vector<std::tuple<std::string, std::string, std::string>>{
             {"units", "furlong", "furlong"},
             {"up", "w", "'w'"},
             {"source_fps", "-1", "-1"},
             {"trim", "5..3", "FIRST..LAST"},
             {"fps", "-1", "-1"},
             {"output_fps", "-1", "-1"},
             {"output_units", "furlong", "furlong"}}) {
      // A graph that writes no clip (graphs/inspect.yaml) has no unit or rate to write it in, and
      // one without a solver (convert.yaml, inspect.yaml) no rate to solve at.
      const bool writes = text.find("type: io.export_") != std::string::npos;
      if ((name == "output_units" || name == "output_fps") && !writes) continue;
      if (name == "fps" && text.find("type: retarget.spacetime") == std::string::npos &&
          text.find("type: retime.retime") == std::string::npos)
        continue;
      std::vector<std::string> args = base;
      args.insert(args.end(), {"--set", name + "=" + bad});
      const Result r = kinegraph(args);
      INFO(name << "=" << bad << "\n" << show(r));
      CHECK(r.code == 3);
      CHECK_THAT(r.err, Catch::Contains(expected));
    }
  }
  CHECK(checked >= 7);
}

TEST_CASE("every graph that solves writes at the input's rate by default, retimings solve at 30 Hz",
          "[graphs]") {
  for (const auto& entry : fs::recursive_directory_iterator(kSource / "graphs")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string text = read_file(entry.path());
    if (text.find("\n  input:") == std::string::npos) continue;
    if (text.find("type: retarget.spacetime") == std::string::npos &&
        text.find("type: retime.retime") == std::string::npos)
      continue;
    INFO(entry.path().string());
    const auto default_of = [&text](const std::string& name) -> std::string {
      const std::size_t at = text.find("\n  " + name + ":");
      if (at == std::string::npos) return "(not declared)";
      const std::size_t open = text.find("default: \"", at);
      return open == std::string::npos ? "(no default)"
                                       : text.substr(open + 10, text.find('"', open + 10) - open - 10);
    };
    // Retargeting solves every frame written (the input's rate): at 30 Hz, a capture's jitter
    // between the solve's frames would stay in the plants written at 120 Hz (02_01.bvh: 2.8 cm).
    const bool retargets = text.find("type: retarget.spacetime") != std::string::npos;
    CHECK(default_of("fps") == (retargets ? "0" : "30"));
    CHECK(default_of("output_fps") == "0");
  }
}
