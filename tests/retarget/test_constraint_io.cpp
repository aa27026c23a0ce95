// Constraint files: every kind read with joints by name, frames, times and lists; the errors
// table; joint limits from skeletons (ASF) and YAML; the retarget.constraints and
// retarget.merge_constraints nodes.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "../support/fuzzed_patterns.hpp"
#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

const synth::Synthesis& walk() {
  static const synth::Synthesis w =
      synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 30});
  return w;
}

ConstraintSet read(const std::string& text) {
  return read_constraints_string(text, "c.yaml", std::span(&walk().motion, 1));
}

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

TEST_CASE("constraint file: all seven kinds, joints by name, frames, times and lists") {
  const motion::Skeleton& sk = *walk().motion.skeleton;
  const ConstraintSet set = read(R"(
version: 1
doc: every kind once
constraints:
  - kind: position
    label: toe on the box
    points: [{joint: LeftToeBase, offset: [0, 0, 0.05]}]
    params: [0.1, 0.2, 0.3, 1, 1, 1]
    frames: [10, 14]
  - kind: region
    points: [{joint: RightToeBase, end_site: true}]
    params: [-.inf, 0, -.inf, .inf, .inf, .inf]
    at_frames: [1, 5, 9]
  - kind: same_place
    points: [{joint: LeftFoot}]
    params: [1, 0, 1]
    times: [0.5, 0.6]
  - kind: follow_path
    relation: at_least
    points: [{joint: LeftHand}, {joint: RightHand, frame_offset: 2}]
    params: [0, 0, 0, 0, 1, 0]
    at_times: [1.0]
    weight: 2.5
  - kind: distance
    points: [{joint: LeftHand}, {joint: RightHand}]
    params: [0.4]
    relation: at_most
    frames: [0, 0]
  - kind: orientation
    points: [{joint: Hips}, {joint: Head}]
    params: [0, 1, 0, 0.3]
    relation: at_most
    frames: [3, 4]
  - kind: parameter_range
    channels: ["LeftLeg.Xrotation", {joint: RightLeg, channel: Xrotation}]
    params: [-0.1, 2.5]
    frames: [0, 1]
  - kind: ladder.rung
    points: [{joint: LeftToeBase}]
    params: [1, 2, 3, 4, 5]
    frames: [2, 3]
)");
  REQUIRE(set.constraints.size() == 8);
  const Constraint& pos = set.constraints[0];
  CHECK(pos.label == "toe on the box");
  CHECK(pos.points[0].joint == sk.find_joint("LeftToeBase"));
  CHECK(pos.points[0].local.isApprox(Eigen::Vector3d(0, 0, 0.05)));
  REQUIRE(pos.samples.size() == 5);
  CHECK(pos.samples[0].frames == std::vector<int>{10});
  CHECK(pos.samples[4].frames == std::vector<int>{14});

  const Constraint& region = set.constraints[1];
  CHECK(region.label == "region 1");
  CHECK(region.points[0].local.isApprox(sk.joint(sk.find_joint("RightToeBase")).end_sites.front()));
  CHECK(std::isinf(region.params[0]));
  CHECK(region.params[1] == 0);
  REQUIRE(region.samples.size() == 3);
  CHECK(region.samples[2].frames == std::vector<int>{9});

  // same_place with one point: the point twice, consecutive frames 15..18 (0.5 s, 0.6 s at 30 Hz).
  const Constraint& same = set.constraints[2];
  REQUIRE(same.points.size() == 2);
  CHECK(same.points[0].joint == same.points[1].joint);
  REQUIRE(same.samples.size() == 3);
  CHECK(same.samples[0].frames == std::vector<int>{15, 16});
  CHECK(same.samples[2].frames == std::vector<int>{17, 18});

  const Constraint& follow = set.constraints[3];
  CHECK(follow.relation == Relation::AtLeast);
  CHECK(follow.weight == 2.5);
  REQUIRE(follow.samples.size() == 1);
  CHECK(follow.samples[0].frames == std::vector<int>{30, 32});  // the lag of frame_offset

  CHECK(set.constraints[4].relation == Relation::AtMost);
  CHECK(set.constraints[4].samples.size() == 1);
  CHECK(set.constraints[5].params.size() == 4);

  const Constraint& range = set.constraints[6];
  REQUIRE(range.channels.size() == 2);
  const int left_leg = sk.find_joint("LeftLeg");
  CHECK(range.channels[0].channel == sk.joint(left_leg).first_channel + 1);  // ZXY: Xrotation second
  CHECK(sk.channel_name(range.channels[1].channel) == "RightLeg.Xrotation");
  CHECK(range.samples[1].frames == std::vector<int>{1, 1});

  // A plugin kind passes through unchecked, its params as given.
  CHECK(set.constraints[7].kind == "ladder.rung");
  CHECK(set.constraints[7].params == std::vector<double>{1, 2, 3, 4, 5});

  // Every built-in one is valid and evaluable on the clip.
  ConstraintSet builtins = set;
  builtins.constraints.pop_back();
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  CHECK_NOTHROW(check_constraints(builtins, kinds));
  CHECK_NOTHROW(summarize_violations(builtins, kinds, std::span(&walk().motion, 1)));
  CHECK_THROWS_WITH(check_constraints(set, kinds), Catch::Contains("unknown kind 'ladder.rung'"));
}

TEST_CASE("constraint file: limits by regular expression, in degrees") {
  const motion::Skeleton& sk = *walk().motion.skeleton;
  const ConstraintSet set = read(R"(
version: 1
limits:
  "(Left|Right)Leg": {Xrotation: [0, 150]}
  "LeftFoot": {Zrotation: [-.inf, 30]}
)");
  REQUIRE(set.constraints.size() == 3);
  const Constraint& c = set.constraints[0];
  CHECK(c.kind == "parameter_range");
  CHECK(c.label == "limit LeftLeg.Xrotation");
  CHECK(c.params[0] == 0);
  CHECK(c.params[1] == Approx(150 * std::numbers::pi / 180));
  CHECK(static_cast<int>(c.samples.size()) == walk().motion.frame_count());
  CHECK(set.constraints[1].label == "limit RightLeg.Xrotation");
  CHECK(std::isinf(set.constraints[2].params[0]));
  CHECK(sk.channel_name(set.constraints[2].channels[0].channel) == "LeftFoot.Zrotation");
  CHECK_NOTHROW(check_constraints(set, ConstraintKindTable::builtin()));
}

TEST_CASE("constraint file errors name file:line:column and what was expected") {
  struct Case {
    const char* text;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftToe}]\n    params: [0, 0, 0]\n"
       "    frames: [1, 2]\n",
       "c.yaml:4:22: unknown joint 'LeftToe' (nearest: 'LeftToeBase')"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, 0, "
       "0]\n"
       "    frames: [5, 2]\n",
       "c.yaml:6:13: constraints[0].frames: the range [5, 2] is reversed"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, 0, "
       "0]\n"
       "    frames: [5, 100000]\n",
       "is outside the clip (frames 0.."},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, 0, "
       "0]\n"
       "    frames: [1, 2, 3]\n",
       "frames: expected [first, last], got 3 entries"},
      {"version: 1\nconstraints:\n  - kind: position\n    pionts: [{joint: LeftFoot}]\n",
       "c.yaml:4:5: unknown key 'constraints[0].pionts' (did you mean 'points'?)"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, 0]\n"
       "    frames: [1, 2]\n",
       "c.yaml:3:5: constraints[0]: constraint 'position 0' (position): expects params [x y z] or [x y z mx "
       "my mz], "
       "got 2 numbers"},
      {"version: 1\nconstraints:\n  - kind: distance\n    points: [{joint: LeftFoot}, {joint: Head}]\n"
       "    params: [1]\n",
       "missing frames"},
      {"version: 1\nconstraints:\n  - kind: distance\n    points: [{joint: LeftFoot}, {joint: Head}]\n"
       "    params: [1]\n    frames: [1, 2]\n    times: [0, 1]\n",
       "give only one of frames, at_frames, times, at_times"},
      {"version: 2\n", "c.yaml:1:10: unsupported version 2"},
      {"constraints: []\n", "missing 'version: 1'"},
      {"version: 1\nconstraint: []\n", "unknown key 'constraint' (did you mean 'constraints'?)"},
      {"version: 1\nconstraints:\n  - kind: parameter_range\n    channels: [LeftLeg.Xrot]\n    params: [0, "
       "1]\n"
       "    frames: [0, 1]\n",
       "joint 'LeftLeg' has no channel 'Xrot' (it has: Zrotation, Xrotation, Yrotation)"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot, offset: [0, 1]}]\n"
       "    params: [0, 0, 0]\n    frames: [0, 1]\n",
       "offset: expected [x, y, z] (metres), got 2 numbers"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot, character: 1}]\n"
       "    params: [0, 0, 0]\n    frames: [0, 1]\n",
       "character 1 does not exist (1 given)"},
      {"version: 1\nconstraints:\n  - kind: position\n    relation: above\n    points: [{joint: LeftFoot}]\n"
       "    params: [0, 0, 0]\n    frames: [0, 1]\n",
       "c.yaml:4:15: constraints[0].relation: relation 'above': expected equal, at_least or at_most"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, x, "
       "0]\n"
       "    frames: [0, 1]\n",
       "constraints[0].params: expected a number, got 'x'"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n    params: [0, 0, "
       "0]\n"
       "    frames: [0.5, 1]\n",
       "expected an integer, got '0.5'"},
      {"version: 1\nlimits:\n  \"Lef(tLeg\": {Xrotation: [0, 1]}\n", "bad regular expression"},
      {"version: 1\nlimits:\n  \"LeftLegg\": {Xrotation: [0, 1]}\n",
       "c.yaml:3:3: limits: 'LeftLegg' matches no joint (nearest: 'LeftLeg')"},
      {"version: 1\nlimits:\n  \"Hips\": {Xrotation: [10, 1]}\n", "expected [min, max] with min <= max"},
      {"version: 1\nlimits:\n  \"Hips\": {Xrot: [0, 1]}\n", "unknown channel 'Xrot'"},
      {"version: 1\nconstraints: [\n", "c.yaml:"},
      // Fuzzing (issue 13): numbers that overflowed int or wrapped into the clip.
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot, frame_offset: "
       "2147483647}]\n"
       "    params: [0, 0, 0]\n    frames: [0, 1]\n",
       "c.yaml:4:46: constraints[0].points[0].frame_offset: 2147483647 is outside -"},
      {"version: 1\nconstraints:\n  - kind: parameter_range\n"
       "    channels: [{joint: LeftLeg, channel: Xrotation, frame_offset: -2147483648}]\n"
       "    params: [0, 1]\n    frames: [0, 1]\n",
       "c.yaml:4:67: constraints[0].channels[0].frame_offset: -2147483648 is outside -"},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n"
       "    params: [0, 0, 0]\n    at_times: [1e300]\n",
       "c.yaml:6:16: constraints[0].at_times: 1e+300 s is outside the clip (0.."},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n"
       "    params: [0, 0, 0]\n    times: [35791394.2, 35791394.3]\n",
       "c.yaml:6:13: constraints[0].times: 35791394.2 s is outside the clip (0.."},
      {"version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n"
       "    params: [0, 0, 0]\n    frames: [0, 2147483647]\n",
       "c.yaml:6:13: constraints[0].frames: the range [0, 2147483647] is outside the clip (frames 0.."},
      {"version: 1\nconstraints:\n  - kind: same_place\n    points: [{joint: LeftFoot, frame_offset: -1}]\n"
       "    at_frames: [-2147483648, 0]\n",
       "c.yaml:5:16: constraints[0]: frame -2147483649 is outside the clip (frames 0.."},
      {"", "empty constraint file"},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    try {
      read(c.text);
      FAIL("no error");
    } catch (const kg::Error& e) {
      CHECK_THAT(std::string(e.what()), Catch::Contains(c.message));
      CHECK(e.where().file == "c.yaml");
    }
  }
}

TEST_CASE("constraint file: fuzzed limits patterns refused at their key with a short excerpt") {
  const auto start = std::chrono::steady_clock::now();
  for (const kg::test::FuzzedPattern& p : kg::test::fuzzed_patterns()) {
    std::string message = "no kg::Error";
    try {
      read("version: 1\nlimits:\n  LeftLeg: {Xrotation: [0, 1]}\n" +
           kg::test::explicit_entry(p.text, "{Xrotation: [0, 1]}", 2));
    } catch (const kg::Error& e) {
      message = e.what();
    }
    kg::test::check_refusal(message, "c.yaml:4:5: limits: ", p);
  }
  CHECK(kg::test::seconds_since(start) < 10);
}

TEST_CASE("constraint files on disk, joint limits from skeletons, merging") {
  test::TempDir dir;
  const auto path =
      dir.write("plants.yaml",
                "version: 1\nconstraints:\n  - kind: position\n    points: [{joint: LeftFoot}]\n"
                "    params: [0, 0.08, 0, 0, 1, 0]\n    frames: [0, 3]\n");
  ConstraintSet set = read_constraints_file(path.string(), std::span(&walk().motion, 1));
  REQUIRE(set.constraints.size() == 1);
  CHECK_THROWS_WITH(read_constraints_file((dir / "absent.yaml").string(), std::span(&walk().motion, 1)),
                    Catch::Contains("absent.yaml") && Catch::Contains("no such constraint file"));

  // A skeleton with limits: one constraint per limited channel, every frame.
  motion::Skeleton sk;
  sk.add_joint(
      {.name = "root", .parent = -1, .channels = {{motion::ChannelKind::Xposition}}, .end_sites = {}});
  sk.add_joint({.name = "knee",
                .parent = 0,
                .channels = {{motion::ChannelKind::Xrotation, 0.0, 2.5},
                             {motion::ChannelKind::Yrotation},
                             {motion::ChannelKind::Zrotation, -kInf, 0.3}},
                .end_sites = {}});
  const ConstraintSet limits = joint_limit_constraints(sk, 1, 7);
  REQUIRE(limits.constraints.size() == 2);
  CHECK(limits.constraints[0].label == "limit knee.Xrotation");
  CHECK(limits.constraints[0].channels[0].channel == 1);
  CHECK(limits.constraints[0].channels[0].character == 1);
  CHECK(limits.constraints[0].params == std::vector<double>{0.0, 2.5});
  CHECK(limits.constraints[1].channels[0].channel == 3);
  CHECK(limits.constraints[1].samples.size() == 7);
  CHECK(limits.character_count() == 2);
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  CHECK_NOTHROW(check_constraints(limits, kinds));
  // One row per finite bound.
  CHECK(kinds.find("parameter_range")->rows(limits.constraints[0]) == 2);
  CHECK(kinds.find("parameter_range")->rows(limits.constraints[1]) == 1);

  merge_constraints(set, limits);
  CHECK(set.constraints.size() == 3);
  CHECK(set.constraints[2].label == "limit knee.Zrotation");

  // ASF limits of a real skeleton.
  const std::string asf = std::string(KG_DATA_DIR) + "/cmu/asf_amc/07.asf";
  const std::string amc = std::string(KG_DATA_DIR) + "/cmu/asf_amc/07_05.amc";
  if (!std::filesystem::exists(amc)) {
    WARN("skipped: " << amc << " not found");
    return;
  }
  const motion::Motion m = io::import_motion(amc, asf, io::ImportOptions{}).motion;
  const ConstraintSet asf_limits = joint_limit_constraints(*m.skeleton, 0, m.frame_count());
  CHECK(asf_limits.constraints.size() > 30);  // CMU ASF: limits on nearly every rotation DOF
  CHECK_NOTHROW(check_constraints(asf_limits, kinds));
  // The captured motion mostly respects its own limits (CMU clips exceed a few slightly).
  const ViolationSummary v = summarize_violations(asf_limits, kinds, std::span(&m, 1));
  const KindViolation* range = v.find("parameter_range");
  REQUIRE(range != nullptr);
  INFO("worst " << range->worst << " rad at " << range->worst_label << ", violated rows "
                << range->violated_rows << " of " << range->rows);
  CHECK(range->violated_rows < range->rows / 10);

  // Joint names of the ASF resolve, with the nearest name for a misspelt one.
  const std::string text =
      "version: 1\nconstraints:\n  - kind: position\n    points: [{joint: ltoes, end_site: true}]\n"
      "    params: [0, 0, 0, 0, 1, 0]\n    times: [1.0, 1.5]\n";
  const ConstraintSet on_asf = read_constraints_string(text, "asf.yaml", std::span(&m, 1));
  REQUIRE(on_asf.constraints.size() == 1);
  CHECK(on_asf.constraints[0].points[0].joint == m.skeleton->find_joint("ltoes"));
  CHECK(static_cast<double>(on_asf.constraints[0].samples.front().frames[0]) ==
        Approx(std::round(1.0 * m.fps)));
  std::string misspelt = text;
  misspelt.replace(misspelt.find("ltoes"), 5, "ltoe");
  CHECK_THROWS_WITH(
      read_constraints_string(misspelt, "asf.yaml", std::span(&m, 1)),
      Catch::Contains("asf.yaml:4:") && Catch::Contains("unknown joint 'ltoe' (nearest: 'ltoes')"));
}

TEST_CASE("retarget.constraints and retarget.merge_constraints nodes") {
  const graph::Registry registry = test::registry_of(retarget_constraint_node_types());
  test::TempDir dir;
  const auto path = dir.write("c.yaml",
                              "version: 1\nconstraints:\n  - kind: distance\n    points: [{joint: LeftHand}, "
                              "{joint: RightHand}]\n    params: [0.5]\n    frames: [0, 9]\n");
  const graph::Value motion = graph::Value::make(walk().motion);
  test::NodeContext ctx = test::run_node(
      registry, "retarget.constraints",
      test::params_for(registry, "retarget.constraints", {{"path", path.string()}}), {{"motion", motion}});
  const ConstraintSet& a = ctx.outputs.at("constraints").get<ConstraintSet>();
  REQUIRE(a.constraints.size() == 1);
  CHECK(std::get<std::int64_t>(ctx.figures.at("samples")) == 10);

  // Merged with an input set; the synthesized figure has no channel limits, which is said.
  test::NodeContext ctx2 = test::run_node(
      registry, "retarget.constraints",
      test::params_for(registry, "retarget.constraints", {{"path", path.string()}, {"joint_limits", true}}),
      {{"motion", motion}, {"constraints", ctx.outputs.at("constraints")}});
  CHECK(ctx2.outputs.at("constraints").get<ConstraintSet>().constraints.size() == 2);
  CHECK(ctx2.logged("no channel limits"));

  test::NodeContext merged =
      test::run_node(registry, "retarget.merge_constraints", {},
                     {{"a", ctx.outputs.at("constraints")}, {"c", ctx2.outputs.at("constraints")}});
  CHECK(merged.outputs.at("constraints").get<ConstraintSet>().constraints.size() == 3);
  CHECK(std::get<std::string>(merged.figures.at("kinds")) == "distance 3");

  // A bad file fails the node with file:line.
  const auto bad =
      dir.write("bad.yaml", "version: 1\nconstraints:\n  - kind: distance\n    points: [{joint: Nose}]\n");
  CHECK_THROWS_WITH(
      test::run_node(registry, "retarget.constraints",
                     test::params_for(registry, "retarget.constraints", {{"path", bad.string()}}),
                     {{"motion", motion}}),
      Catch::Contains("bad.yaml:4:") && Catch::Contains("unknown joint 'Nose'"));
}
