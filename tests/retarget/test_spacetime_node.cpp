// The node retarget.spacetime: ports, params, masks, reports, and errors, on the synthesized walk
// with the built-in constraint kinds.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>

#include "../support/fuzzed_patterns.hpp"
#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

struct Walk60 {
  motion::Motion m1;
  ConstraintSet plants;
  synth::Synthesis walk;
};

// The synthesized walk at 30 Hz on a 60% figure whose thighs and shanks are a further 15%
// shorter, with fixed position constraints at the original plants scaled about the origin.
Walk60 walk60() {
  Walk60 w;
  w.walk = synth::synthesize_walk({.steps = 3, .speed = 1.2, .stature = 1.75, .fps = 30});
  const double s = 0.6;
  auto target = std::make_shared<motion::Skeleton>(*w.walk.motion.skeleton);
  for (int j = 0; j < target->joint_count(); ++j) {
    motion::Joint& jt = target->joint_mut(j);
    const bool leg = j == w.walk.figure.leg[0] || j == w.walk.figure.leg[1] || j == w.walk.figure.foot[0] ||
                     j == w.walk.figure.foot[1];
    jt.offset *= leg ? s * 0.85 : s;
    for (Eigen::Vector3d& e : jt.end_sites) e *= s;
  }
  w.m1 = {target, w.walk.motion.values, 30, "walk60"};
  w.m1.values.leftCols(3) *= s;
  for (const synth::FootPlant& p : w.walk.plants) {
    const Eigen::Vector3d at = p.world * s;
    Constraint c{.kind = "position",
                 .label = p.name() + " plant",
                 .points = {{0, p.joint, p.local * s}},
                 .params = {at.x(), at.y(), at.z()}};
    for (int f = p.first_frame; f <= p.last_frame; ++f) c.samples.push_back({{f}});
    w.plants.constraints.push_back(c);
  }
  return w;
}

bool logged(const test::NodeContext& ctx, const std::string& part) {
  for (const std::string& line : ctx.logs)
    if (line.find(part) != std::string::npos) return true;
  return false;
}

const graph::NodeType& spacetime_node() {
  static const graph::Registry registry = test::registry_of(retarget_spacetime_node_types());
  return test::node_type(registry, "retarget.spacetime");
}

}  // namespace

TEST_CASE("retarget.spacetime node: solves, reports, honours a freeze mask", "[spacetime][node]") {
  const Walk60 w = walk60();
  const graph::NodeType& type = spacetime_node();
  CHECK(type.spec.find_input("motion2") != nullptr);
  CHECK_FALSE(type.spec.find_input("motion2")->required);

  test::NodeContext ctx = test::run_node(
      type,
      test::params_for(type.spec,
                       {{"freeze", std::string("(Left|Right)(Shoulder|Arm|ForeArm|Hand)|Neck|Head")}}),
      {{"motion", graph::Value::make(w.m1)}, {"constraints", graph::Value::make(w.plants)}});
  INFO(std::get<std::string>(ctx.figures.at("message")));
  CHECK(std::get<bool>(ctx.figures.at("converged")));
  CHECK(std::get<double>(ctx.figures.at("worst_violation_mm")) <= 1.0);
  CHECK(std::get<double>(ctx.figures.at("worst_mm.position")) <= 1.0);
  CHECK(std::get<std::int64_t>(ctx.figures.at("iterations")) >= 1);
  CHECK(std::get<std::int64_t>(ctx.figures.at("finest_keys")) == 4);
  CHECK(logged(ctx, "converged in"));
  CHECK(ctx.outputs.count("motion2") == 0);
  const motion::Motion& out = ctx.outputs.at("motion").get<motion::Motion>();
  REQUIRE(out.frame_count() == w.m1.frame_count());
  // Frozen joints' channels are untouched, and the legs did change.
  const motion::Skeleton& sk = *out.skeleton;
  for (const char* name : {"LeftArm", "RightForeArm", "Neck", "Head", "LeftShoulder"}) {
    const motion::Joint& jt = sk.joint(sk.find_joint(name));
    for (std::size_t c = 0; c < jt.channels.size(); ++c)
      CHECK(out.values.col(jt.first_channel + static_cast<int>(c)) ==
            w.m1.values.col(jt.first_channel + static_cast<int>(c)));
  }
  const int knee = sk.joint(w.walk.figure.leg[0]).first_channel;
  CHECK((out.values.col(knee + 1) - w.m1.values.col(knee + 1)).cwiseAbs().maxCoeff() > 1e-3);
}

TEST_CASE("retarget.spacetime node: fuzzed freeze patterns refused when made, with a short excerpt",
          "[spacetime][node]") {
  const graph::NodeType& type = spacetime_node();
  const auto start = std::chrono::steady_clock::now();
  for (const test::FuzzedPattern& p : test::fuzzed_patterns())
    for (const std::string param : {"freeze", "freeze2"}) {
      std::string message = "no std::invalid_argument";
      try {
        type.create(test::params_for(type.spec, {{param, p.text}}));
      } catch (const std::invalid_argument& e) {
        message = e.what();
      }
      test::check_refusal(message, param + ": ", p);
    }
  CHECK(test::seconds_since(start) < 10);
}

TEST_CASE("retarget.spacetime node: key spacing input, contradictions reported, bad wiring refused",
          "[spacetime][node]") {
  const Walk60 w = walk60();
  const graph::NodeType& type = spacetime_node();
  const int channels = w.m1.skeleton->channel_count();

  SECTION("a contradictory set is reported as not converged, not thrown") {
    ConstraintSet set = w.plants;
    Constraint twice = set.constraints[0];
    twice.label = "elsewhere";
    twice.params[0] += 0.5;
    set.constraints.push_back(twice);
    KeySpacing keys{std::vector<int>(static_cast<std::size_t>(channels), 8), "by hand"};
    test::NodeContext ctx = test::run_node(
        type, test::params_for(type.spec, {{"max_iterations", std::int64_t{10}}, {"densify", false}}),
        {{"motion", graph::Value::make(w.m1)},
         {"constraints", graph::Value::make(set)},
         {"keys", graph::Value::make(keys)}});
    CHECK_FALSE(std::get<bool>(ctx.figures.at("converged")));
    CHECK(std::get<std::int64_t>(ctx.figures.at("finest_keys")) == 8);
    CHECK(std::get<double>(ctx.figures.at("worst_violation_mm")) > 100);
    CHECK(logged(ctx, "did not converge"));
    CHECK(logged(ctx, "'elsewhere'"));
    CHECK(ctx.outputs.count("motion") == 1);
  }
  SECTION("key spacing of the wrong size") {
    KeySpacing keys{{4, 4}, "by hand"};
    CHECK_THROWS_WITH(test::run_node(type, test::params_for(type.spec),
                                     {{"motion", graph::Value::make(w.m1)},
                                      {"constraints", graph::Value::make(w.plants)},
                                      {"keys", graph::Value::make(keys)}}),
                      Catch::Contains("2 key spacings") && Catch::Contains("66 channels"));
  }
  SECTION("a second character's constraints without motion2") {
    ConstraintSet set = w.plants;
    set.constraints[0].points[0].character = 1;
    CHECK_THROWS_WITH(
        test::run_node(type, test::params_for(type.spec),
                       {{"motion", graph::Value::make(w.m1)}, {"constraints", graph::Value::make(set)}}),
        Catch::Contains("motion2"));
  }
  SECTION("freeze patterns that are invalid or match nothing") {
    CHECK_THROWS_WITH(type.create(test::params_for(type.spec, {{"freeze", std::string("(Left")}})),
                      Catch::Contains("freeze") && Catch::Contains("regular expression"));
    CHECK_THROWS_WITH(test::run_node(type, test::params_for(type.spec, {{"freeze2", std::string("Tail")}}),
                                     {{"motion", graph::Value::make(w.m1)},
                                      {"motion2", graph::Value::make(w.m1)},
                                      {"constraints", graph::Value::make(w.plants)}}),
                      Catch::Contains("freeze2") && Catch::Contains("matches no joint"));
  }
  SECTION("an unknown constraint kind is named") {
    ConstraintSet set = w.plants;
    set.constraints[0].kind = "levitate";
    CHECK_THROWS_WITH(
        test::run_node(type, test::params_for(type.spec),
                       {{"motion", graph::Value::make(w.m1)}, {"constraints", graph::Value::make(set)}}),
        Catch::Contains("levitate"));
  }
}

TEST_CASE("retarget.spacetime node: two characters, hand-hold distance, second one's lower body frozen",
          "[spacetime][node]") {
  const Walk60 w = walk60();
  const graph::NodeType& type = spacetime_node();
  // The second character walks 0.5 m to the first one's left; their hands must stay 0.45 m apart.
  motion::Motion m2 = w.m1;
  m2.values.col(0).array() += 0.5;
  ConstraintSet set = w.plants;
  Constraint hold{.kind = "distance",
                  .label = "hand-hold",
                  .points = {{0, w.walk.figure.hand[synth::kLeft], {0, 0, 0}},
                             {1, w.walk.figure.hand[synth::kRight], {0, 0, 0}}},
                  .params = {0.45}};
  for (int f = 0; f < w.m1.frame_count(); ++f) hold.samples.push_back({{f, f}});
  set.constraints.push_back(hold);
  test::NodeContext ctx = test::run_node(
      type,
      test::params_for(type.spec, {{"freeze2", std::string("Hips|(Left|Right)(UpLeg|Leg|Foot|ToeBase)")}}),
      {{"motion", graph::Value::make(w.m1)},
       {"motion2", graph::Value::make(m2)},
       {"constraints", graph::Value::make(set)}});
  INFO(std::get<std::string>(ctx.figures.at("message")));
  CHECK(std::get<bool>(ctx.figures.at("converged")));
  REQUIRE(ctx.outputs.count("motion2") == 1);
  const motion::Motion& a = ctx.outputs.at("motion").get<motion::Motion>();
  const motion::Motion& b = ctx.outputs.at("motion2").get<motion::Motion>();
  std::vector<Eigen::Isometry3d> wa(static_cast<std::size_t>(a.skeleton->joint_count())), wb(wa.size());
  for (int f = 0; f < a.frame_count(); f += 7) {
    motion::forward_kinematics(*a.skeleton, a.values.row(f), wa);
    motion::forward_kinematics(*b.skeleton, b.values.row(f), wb);
    const double d = (wa[static_cast<std::size_t>(w.walk.figure.hand[synth::kLeft])].translation() -
                      wb[static_cast<std::size_t>(w.walk.figure.hand[synth::kRight])].translation())
                         .norm();
    CHECK(d == Approx(0.45).margin(1e-3));
  }
  const int hips = b.skeleton->joint(0).first_channel;
  for (int c = hips; c < hips + 6; ++c) CHECK(b.values.col(c) == m2.values.col(c));
  CHECK((b.values - m2.values).cwiseAbs().maxCoeff() > 1e-3);  // its upper body moved
}
