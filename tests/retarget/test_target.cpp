// retarget.target: uniform, per-bone (regex, default, first match), lengths, skeleton files,
// morphs, and the YAML error table.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>

#include "../support/fuzzed_patterns.hpp"
#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/error.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/target.hpp"
#include "kg/synth/figure.hpp"
#include "kg/synth/synthesize.hpp"

namespace fs = std::filesystem;
using kg::retarget::LoadedTarget;
using kg::retarget::Target;

namespace {

kg::synth::Figure figure() {
  return kg::synth::make_figure(1.75);
}

int joint(const kg::motion::Skeleton& s, const std::string& name) {
  const int j = s.find_joint(name);
  REQUIRE(j >= 0);
  return j;
}

// The message of what `f` throws, "" when it does not throw.
template <class F>
std::string thrown(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

const fs::path kData = KG_DATA_DIR;

}  // namespace

TEST_CASE("uniform target scales every offset and end site, overall scale is the factor",
          "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  const Target t = kg::retarget::uniform_target(fig.skeleton, 0.6);
  REQUIRE(t.skeleton->joint_count() == fig.skeleton->joint_count());
  for (int j = 0; j < fig.skeleton->joint_count(); ++j) {
    CHECK((t.skeleton->joint(j).offset - 0.6 * fig.skeleton->joint(j).offset).norm() < 1e-12);
    for (std::size_t e = 0; e < fig.skeleton->joint(j).end_sites.size(); ++e)
      CHECK((t.skeleton->joint(j).end_sites[e] - 0.6 * fig.skeleton->joint(j).end_sites[e]).norm() < 1e-12);
    CHECK(t.skeleton->joint(j).channels.size() == fig.skeleton->joint(j).channels.size());
  }
  CHECK(t.overall_scale(0.0) == Approx(0.6).epsilon(1e-12));
  CHECK(t.overall_scale(12.0) == Approx(0.6).epsilon(1e-12));
  CHECK(t.skeleton_at(3.0) == t.skeleton);
  CHECK((t.joint_factors(0.0).array() - 0.6).abs().maxCoeff() < 1e-12);
  CHECK_FALSE(t.morphing());
  // The rest hip height of the synthetic figure is its root height (toe tips on the floor).
  CHECK(kg::retarget::rest_hip_height(*fig.skeleton) == Approx(fig.dims.rest_root_height()).epsilon(1e-9));
  CHECK(thrown([&] {
          kg::retarget::uniform_target(fig.skeleton, 0.0);
        }).find("expected a finite number > 0") != std::string::npos);
  CHECK(!thrown([&] { kg::retarget::uniform_target(fig.skeleton, -1.0); }).empty());
}

TEST_CASE("bones YAML: whole-name regex, first match wins, default for the rest", "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  const auto& s = *fig.skeleton;
  const std::string text =
      "version: 1\n"
      "default: 0.9\n"
      "bones:\n"
      "  \"(Left|Right)(Leg|Foot)\": 0.7\n"
      "  \"Left.*\": 1.1\n"
      "  \"Spine|Chest|Neck\": 1.2\n";
  const LoadedTarget lt = kg::retarget::parse_target_yaml(fig.skeleton, text, "short.yaml");
  CHECK(lt.kind == "bones");
  const Eigen::VectorXd f = lt.target.joint_factors(0.0);
  CHECK(f[joint(s, "LeftLeg")] == Approx(0.7));  // first pattern, though Left.* matches too
  CHECK(f[joint(s, "RightFoot")] == Approx(0.7));
  CHECK(f[joint(s, "LeftArm")] == Approx(1.1));
  CHECK(f[joint(s, "LeftToeBase")] == Approx(1.1));
  CHECK(f[joint(s, "RightArm")] == Approx(0.9));  // default
  CHECK(f[joint(s, "Hips")] == Approx(0.9));
  CHECK(f[joint(s, "Spine")] == Approx(1.2));
  CHECK(f[joint(s, "Head")] == Approx(0.9));  // "Neck" must match the whole name
  // The factor scales the joint's offset and its End Site.
  const int toe = joint(s, "LeftToeBase");
  REQUIRE(s.joint(toe).end_sites.size() == 1);
  CHECK((lt.target.skeleton->joint(toe).end_sites[0] - 1.1 * s.joint(toe).end_sites[0]).norm() < 1e-12);
  CHECK((lt.target.skeleton->joint(toe).offset - 1.1 * s.joint(toe).offset).norm() < 1e-12);
  // A note names what each pattern matched, and what an earlier one had taken.
  bool noted = false;
  for (const std::string& n : lt.notes)
    noted = noted || (n.find("Left.*") != std::string::npos &&
                      n.find("already matched earlier: LeftLeg") != std::string::npos);
  CHECK(noted);

  // Overall scale: the hip height of the target over the source's, from the rest pose's lowest
  // point (the left toe tip) up to the root: each vertical offset component times its factor.
  double src = 0, tgt = 0;
  for (int j = toe; j >= 0 && s.joint(j).parent >= 0; j = s.joint(j).parent) {
    src += -s.joint(j).offset.y();
    tgt += -s.joint(j).offset.y() * f[j];
  }
  src += -s.joint(toe).end_sites[0].y();
  tgt += -s.joint(toe).end_sites[0].y() * f[toe];
  CHECK(lt.target.overall_scale(0.0) == Approx(tgt / src).epsilon(1e-9));
  CHECK(lt.target.overall_scale(0.0) < 0.95);
}

TEST_CASE("lengths YAML sets absolute offset lengths, keeping directions", "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  const auto& s = *fig.skeleton;
  const std::string text =
      "version: 1\n"
      "lengths:\n"
      "  \"(Left|Right)Leg\": 0.5\n"
      "  LeftToeBase: 0.2\n";
  const LoadedTarget lt = kg::retarget::parse_target_yaml(fig.skeleton, text, "len.yaml");
  CHECK(lt.kind == "lengths");
  for (const char* name : {"LeftLeg", "RightLeg"}) {
    const int j = joint(s, name);
    const Eigen::Vector3d o = lt.target.skeleton->joint(j).offset;
    CHECK(o.norm() == Approx(0.5).epsilon(1e-12));
    CHECK(o.normalized().dot(s.joint(j).offset.normalized()) == Approx(1.0).epsilon(1e-12));
  }
  const int toe = joint(s, "LeftToeBase");
  const double ratio = 0.2 / s.joint(toe).offset.norm();
  CHECK((lt.target.skeleton->joint(toe).end_sites[0] - ratio * s.joint(toe).end_sites[0]).norm() < 1e-12);
  CHECK(lt.target.joint_factors(0.0)[joint(s, "Spine")] == Approx(1.0));  // default default

  // A joint whose source offset is zero has no direction to keep.
  auto tiny = std::make_shared<kg::motion::Skeleton>();
  tiny->add_joint({.name = "root", .parent = -1});
  tiny->add_joint({.name = "joint0", .parent = 0});
  tiny->add_joint({.name = "tip", .parent = 1, .offset = {0, 1, 0}});
  const std::string err = thrown([&] {
    kg::retarget::parse_target_yaml(tiny, "version: 1\nlengths:\n  \"joint.*\": 0.3\n", "zero.yaml");
  });
  CHECK(err.find("zero.yaml:3:3") != std::string::npos);
  CHECK(err.find("zero offset") != std::string::npos);
}

TEST_CASE("morph YAML interpolates factors between keys and holds them outside", "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  const auto& s = *fig.skeleton;
  const std::string text =
      "version: 1\n"
      "default: 1.0\n"
      "morph:\n"
      "  - {time: 0.5, scale: 1.0}\n"
      "  - {time: 2.5, scale: 0.6}\n"
      "  - time: 3.5\n"
      "    bones: {\"Left.*\": 0.5}\n"
      "    default: 0.6\n";
  const LoadedTarget lt = kg::retarget::parse_target_yaml(fig.skeleton, text, "morph.yaml");
  const Target& t = lt.target;
  CHECK(lt.kind == "morph");
  REQUIRE(t.morphing());
  CHECK(t.key_times == std::vector<double>{0.5, 2.5, 3.5});
  REQUIRE(t.key_factors.size() == 3);
  CHECK(t.overall_scale(0.0) == Approx(1.0));  // held before the first key
  CHECK(t.overall_scale(1.5) == Approx(0.8).epsilon(1e-12));
  CHECK(t.overall_scale(2.5) == Approx(0.6).epsilon(1e-12));
  const int leg = joint(s, "LeftLeg"), arm = joint(s, "RightArm");
  CHECK(t.joint_factors(3.0)[leg] == Approx(0.55));
  CHECK(t.joint_factors(3.0)[arm] == Approx(0.6));
  CHECK(t.joint_factors(99.0)[leg] == Approx(0.5));  // held after the last
  const auto mid = t.skeleton_at(1.5);
  CHECK((mid->joint(leg).offset - 0.8 * s.joint(leg).offset).norm() < 1e-12);
  CHECK((t.skeleton->joint(leg).offset - s.joint(leg).offset).norm() < 1e-12);  // the state at time 0
}

TEST_CASE("target YAML errors name file:line:column", "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  struct Case {
    const char* text;
    const char* where;
    const char* says;
  };
  const Case cases[] = {
      {"version: 1\nbonez:\n  Hips: 2\n", "bad.yaml:2:1", "unknown key 'bonez'"},
      {"version: 1\nbones:\n  Hips: 2\n  \"Left(\": 1\n", "bad.yaml:4:3", "bad regular expression 'Left('"},
      {"version: 1\nbones:\n  Hips: 0\n", "bad.yaml:3:9", "expected a number > 0"},
      {"version: 1\nbones:\n  Hips: -0.5\n", "bad.yaml:3:9", "expected a number > 0"},
      {"version: 1\nbones:\n  Hips: tall\n", "bad.yaml:3:9", "expected a number"},
      {"version: 1\ndefault: 0\nbones:\n  Hips: 1\n", "bad.yaml:2:10", "expected a number > 0"},
      {"version: 2\nbones:\n  Hips: 1\n", "bad.yaml:1:10", "unsupported version '2'"},
      {"bones:\n  Hips: 1\n", "bad.yaml:1:1", "missing 'version: 1'"},
      {"version: 1\nbones:\n  Leg: 0.5\n", "bad.yaml:3:3", "matches no joint (the whole name must match)"},
      {"version: 1\nbones:\n  Hips: 1\nlengths:\n  Hips: 1\n", "bad.yaml:4:1", "give only one of"},
      {"version: 1\n", "bad.yaml:1:1", "expected one of 'bones', 'lengths' or 'morph'"},
      {"version: 1\nbones: [1, 2]\n", "bad.yaml:2:8", "bones must be a map"},
      {"version: 1\nbones:\n  Hips: 1\n  Hips: 2\n", "bad.yaml:4:3", "duplicate key 'Hips'"},
      {"version: 1\nmorph:\n  - {time: 1, scale: 1}\n  - {time: 1, scale: 0.5}\n", "bad.yaml:4:12",
       "must increase strictly"},
      {"version: 1\nmorph:\n  - {time: 0, scael: 1}\n", "bad.yaml:3:15",
       "unknown key 'scael' in morph[0] (did you mean 'scale'?)"},
      {"version: 1\nmorph:\n  - {time: 0}\n", "bad.yaml:3:5", "exactly one of 'scale', 'bones' or 'lengths'"},
      {"version: 1\nmorph:\n  - {scale: 1}\n", "bad.yaml:3:5", "missing 'time'"},
      {"version: 1\nmorph:\n  - {time: 0, bones: {Hips: -1}}\n", "bad.yaml:3:29", "expected a number > 0"},
      {"version: 1\nbones: {Hips: 1\n", "bad.yaml:", "malformed YAML"},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    std::string message;
    try {
      kg::retarget::parse_target_yaml(fig.skeleton, c.text, "bad.yaml");
    } catch (const kg::Error& e) {
      message = e.what();
    }
    INFO(message);
    CHECK(message.rfind(c.where, 0) == 0);
    CHECK(message.find(c.says) != std::string::npos);
  }
}

TEST_CASE("target YAML: fuzzed patterns refused at their key with a short excerpt", "[retarget][target]") {
  const kg::synth::Figure fig = figure();
  const auto start = std::chrono::steady_clock::now();
  for (const kg::test::FuzzedPattern& p : kg::test::fuzzed_patterns()) {
    const auto error = [&](const std::string& text) {
      try {
        kg::retarget::parse_target_yaml(fig.skeleton, text, "deep.yaml");
      } catch (const kg::Error& e) {
        return std::string(e.what());
      }
      return std::string("no kg::Error");
    };
    for (const std::string what : {"bones", "lengths"})
      kg::test::check_refusal(error("version: 1\n" + what + ":\n" + kg::test::explicit_entry(p.text, "1", 2)),
                              "deep.yaml:3:5: " + what + ": ", p);
    kg::test::check_refusal(
        error("version: 1\nmorph:\n  - time: 0\n    bones:\n" + kg::test::explicit_entry(p.text, "1", 6)),
        "deep.yaml:5:9: morph[0].bones: ", p);
  }
  CHECK(kg::test::seconds_since(start) < 10);
}

TEST_CASE("skeleton file targets: same structure taken, another refused naming the difference",
          "[retarget][target]") {
  kg::test::TempDir dir;
  // Synthetic figures of two statures have the same structure; write one as BVH.
  const kg::synth::Synthesis small = kg::synth::synthesize_walk({.steps = 2, .stature = 1.4, .fps = 30});
  const kg::synth::Figure big = figure();
  const fs::path bvh = dir.write("small.bvh", kg::io::write_bvh_string(small.motion, {.units = "cm"}));
  const LoadedTarget lt = kg::retarget::load_target(big.skeleton, bvh.string());
  CHECK(lt.kind == "skeleton");
  for (int j = 0; j < big.skeleton->joint_count(); ++j)
    CHECK((lt.target.skeleton->joint(j).offset - small.figure.skeleton->joint(j).offset).norm() < 1e-6);
  CHECK(lt.target.overall_scale(0.0) == Approx(1.4 / 1.75).epsilon(1e-6));

  // Same joint count, another name.
  std::string text = kg::io::write_bvh_string(small.motion, {.units = "cm"});
  const std::size_t at = text.find("LeftHand");
  REQUIRE(at != std::string::npos);
  text.replace(at, 8, "LeftPalm");
  const fs::path renamed = dir.write("renamed.bvh", text);
  const int hand = big.skeleton->find_joint("LeftHand");
  const std::string err = thrown([&] { kg::retarget::load_target(big.skeleton, renamed.string()); });
  CHECK(err.find("joint " + std::to_string(hand) +
                 " is 'LeftPalm' in the target, 'LeftHand' in the source") != std::string::npos);

  CHECK(thrown([&] {
          kg::retarget::load_target(big.skeleton, (dir / "x.txt").string());
        }).find("unknown extension") != std::string::npos);
  CHECK(thrown([&] {
          kg::retarget::load_target(big.skeleton, (dir / "missing.yaml").string());
        }).find("missing.yaml") != std::string::npos);
}

TEST_CASE("CMU skeleton files: 07.asf as a target for 16.asf, the MotionBuilder BVH refused",
          "[retarget][target][data]") {
  const fs::path asf16 = kData / "cmu/asf_amc/16.asf", asf07 = kData / "cmu/asf_amc/07.asf";
  const fs::path mb = kData / "cmu/bvh_motionbuilder/16_15.bvh";
  if (!fs::exists(asf16) || !fs::exists(asf07) || !fs::exists(mb)) {
    WARN("skipped: CMU files not found under " << kData);
    return;
  }
  const kg::io::ImportedMotion src =
      kg::io::import_asf_amc(asf16.string(), (kData / "cmu/asf_amc/16_15.amc").string(), {});
  const auto& s = *src.motion.skeleton;
  const LoadedTarget lt = kg::retarget::load_target(src.motion.skeleton, asf07.string());
  // 07.asf: rfemur length 7.15483 in 0.45-inch units; the femur is rtibia's offset.
  const double metres = 7.15483 * 0.0254 / 0.45;
  CHECK(lt.target.skeleton->joint(s.find_joint("rtibia")).offset.norm() == Approx(metres).epsilon(1e-6));
  CHECK(s.joint(s.find_joint("rtibia")).offset.norm() == Approx(7.12424 * 0.0254 / 0.45).epsilon(1e-6));
  const double scale = lt.target.overall_scale(0.0);
  CHECK(scale ==
        Approx(kg::retarget::rest_hip_height(*lt.target.skeleton) / kg::retarget::rest_hip_height(s)));
  CHECK(scale > 0.9);
  CHECK(scale < 1.1);
  WARN("07.asf against 16.asf: overall scale "
       << scale << ", hip heights " << kg::retarget::rest_hip_height(*lt.target.skeleton) << " m and "
       << kg::retarget::rest_hip_height(s) << " m");

  const std::string err = thrown([&] { kg::retarget::load_target(src.motion.skeleton, mb.string()); });
  INFO(err);
  CHECK(err.find("target skeleton has 29 joints, source 31") != std::string::npos);
}

TEST_CASE("retarget.target node: uniform scale, a file, and the scale it ignores",
          "[retarget][target][node]") {
  const auto registry = kg::test::registry_of(kg::retarget_target_node_types());
  const kg::synth::Synthesis walk = kg::synth::synthesize_walk({.steps = 2, .fps = 30});
  {
    auto ctx = kg::test::run_node(registry, "retarget.target",
                                  kg::test::params_for(registry, "retarget.target", {{"scale", 0.6}}),
                                  {{"motion", kg::graph::Value::make(walk.motion)}});
    const Target& t = ctx.outputs.at("target").get<Target>();
    CHECK(t.overall_scale(0) == Approx(0.6));
    CHECK(std::get<std::string>(ctx.figures.at("kind")) == "uniform");
    CHECK(std::get<double>(ctx.figures.at("overall_scale")) == Approx(0.6));
  }
  kg::test::TempDir dir;
  const fs::path yaml = dir.write("t.yaml", "version: 1\nbones:\n  \".*(Leg|Foot)\": 0.5\n");
  auto ctx = kg::test::run_node(
      registry, "retarget.target",
      kg::test::params_for(registry, "retarget.target", {{"scale", 0.6}, {"target", yaml.string()}}),
      {{"motion", kg::graph::Value::make(walk.motion)}});
  CHECK(std::get<std::string>(ctx.figures.at("kind")) == "bones");
  CHECK(std::get<double>(ctx.figures.at("min_factor")) == Approx(0.5));
  CHECK(ctx.logged("scale 0.6 ignored"));
  CHECK_THROWS(registry.create_node("retarget.target",
                                    kg::test::params_for(registry, "retarget.target", {{"scale", -1.0}})));
}

TEST_CASE("constraints on a morphing target: each sample's points scaled at its frame's time",
          "[retarget][target]") {
  const kg::synth::Synthesis walk =
      kg::synth::synthesize_walk({.steps = 3, .speed = 1.2, .stature = 1.75, .fps = 30});
  const auto& s = *walk.motion.skeleton;
  const int toe = joint(s, "LeftToeBase");
  const Eigen::Vector3d tip = s.joint(toe).end_sites.front();
  // 1.0 at t = 0 down to 0.5 at t = 2 s (frame 60 at 30 Hz).
  const Target morph = kg::retarget::morph_target(
      walk.motion.skeleton, {0.0, 2.0},
      {Eigen::VectorXd::Ones(s.joint_count()), Eigen::VectorXd::Constant(s.joint_count(), 0.5)});
  kg::retarget::Constraint plant{
      .kind = "position", .label = "toe tip", .points = {{0, toe, tip}}, .params = {0, 0, 0, 0, 1, 0}};
  for (int f : {0, 30, 60, 75}) plant.samples.push_back({.frames = {f}});
  kg::retarget::ConstraintSet set;
  set.constraints.push_back(plant);

  CHECK_THAT(thrown([&] { kg::retarget::constraints_on_target(set, morph); }), Catch::Contains("frame rate"));
  const kg::retarget::ConstraintSet moved = kg::retarget::constraints_on_target(set, morph, 0, 30.0);
  const kg::retarget::Constraint& c = moved.constraints.front();
  CHECK((c.points[0].local - tip).norm() < 1e-12);  // the offset at time 0
  REQUIRE(c.samples.size() == 4);
  const double expected[] = {1.0, 0.75, 0.5, 0.5};
  for (std::size_t i = 0; i < 4; ++i) {
    REQUIRE(c.samples[i].locals.size() == 1);
    CHECK((c.samples[i].locals[0] - expected[i] * tip).norm() < 1e-12);
    // Which is the End Site of that frame's skeleton: the real toe tip, not a point ahead of it.
    const auto at = morph.skeleton_at(c.samples[i].frames[0] / 30.0);
    CHECK((c.samples[i].locals[0] - at->joint(toe).end_sites.front()).norm() < 1e-12);
  }
  // Per-sample offsets must match the points, for built-in kinds and the solver alike.
  kg::retarget::ConstraintSet bad = moved;
  bad.constraints.front().samples[1].locals.push_back(tip);
  CHECK_THAT(
      thrown([&] { kg::retarget::check_constraints(bad, kg::retarget::ConstraintKindTable::builtin()); }),
      Catch::Contains("a sample gives 2 point offsets for 1 points"));
  bad.constraints.front().samples[1].locals = {Eigen::Vector3d(NAN, 0, 0)};
  CHECK_THAT(
      thrown([&] { kg::retarget::check_constraints(bad, kg::retarget::ConstraintKindTable::builtin()); }),
      Catch::Contains("point offset is not finite"));

  // A constant target scales the constraint's points and leaves samples alone; the other
  // character's points stay.
  set.constraints.front().points.push_back({1, toe, tip});
  for (auto& sm : set.constraints.front().samples) sm.frames.push_back(sm.frames.front());
  const kg::retarget::ConstraintSet small =
      kg::retarget::constraints_on_target(set, kg::retarget::uniform_target(walk.motion.skeleton, 0.6));
  CHECK((small.constraints.front().points[0].local - 0.6 * tip).norm() < 1e-12);
  CHECK((small.constraints.front().points[1].local - tip).norm() < 1e-12);
  CHECK(small.constraints.front().samples.front().locals.empty());

  // The node needs the clip's frame rate for a morph.
  const kg::graph::Registry registry = kg::test::registry_of(kg::retarget_target_node_types());
  CHECK_THAT(thrown([&] {
               kg::test::run_node(
                   registry, "retarget.constraints_on_target",
                   kg::test::params_for(registry, "retarget.constraints_on_target", {}),
                   {{"constraints", kg::graph::Value::make(set)}, {"target", kg::graph::Value::make(morph)}});
             }),
             Catch::Contains("connect the clip to 'motion'"));
}
