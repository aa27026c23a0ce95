// Per-frame IK baseline (per_frame_ik.hpp): exact answers on a hand-built two-link leg (position,
// region through the active set, same_place solved forward in time), the frames it must not
// touch, bad input, and the synthesizer's walk on a shorter-legged figure with its own plants:
// every constrained frame converges and meets its constraints, and the snaps the paper's §3.1
// describes show up as high-frequency energy in the displacement.
#include <cmath>
#include <cstdint>
#include <filesystem>

#include <catch2/catch.hpp>

#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/footplants.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/per_frame_ik.hpp"
#include "kg/synth/synthesize.hpp"

using Catch::Matchers::Contains;
using namespace kg;
using namespace kg::retarget;
using motion::ChannelKind;
using motion::Motion;

namespace {

// hip (root: X/Y/Z position, X rotation) -> knee (X rotation, 0.5 m below) -> ankle (0.5 m below).
// The leg swings in the Y/Z plane.
Motion two_link_leg(int frames) {
  auto s = std::make_shared<motion::Skeleton>();
  motion::Joint hip;
  hip.name = "hip";
  for (ChannelKind k :
       {ChannelKind::Xposition, ChannelKind::Yposition, ChannelKind::Zposition, ChannelKind::Xrotation})
    hip.channels.push_back({k});
  s->add_joint(hip);
  motion::Joint knee;
  knee.name = "knee";
  knee.parent = 0;
  knee.offset = {0, -0.5, 0};
  knee.channels.push_back({ChannelKind::Xrotation});
  s->add_joint(knee);
  motion::Joint ankle;
  ankle.name = "ankle";
  ankle.parent = 1;
  ankle.offset = {0, -0.5, 0};
  s->add_joint(ankle);
  Motion m{s, motion::FrameMatrix::Zero(frames, s->channel_count()), 30.0, "leg"};
  for (int f = 0; f < frames; ++f) {
    m.values(f, 1) = 1.0;                      // hip 1 m up: the ankle touches y = 0 when straight
    m.values(f, 2) = 0.02 * f;                 // walking along +Z
    m.values(f, 3) = 0.3 * std::sin(0.2 * f);  // hip swings
    m.values(f, 4) = 0.4;                      // knee bent
  }
  return m;
}

Eigen::Vector3d ankle_at(const Motion& m, int f) {
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
  motion::forward_kinematics(*m.skeleton, m.values.row(f), world);
  return world[2].translation();
}

Constraint ankle_constraint(const std::string& kind, std::vector<double> params,
                            std::vector<std::vector<int>> frames) {
  Constraint c;
  c.kind = kind;
  c.label = "ankle " + kind;
  c.points = {{.joint = 2}};
  if (kind == "same_place") c.points.push_back({.joint = 2});
  c.params = std::move(params);
  for (auto& f : frames) c.samples.push_back({.frames = f});
  return c;
}

const ConstraintKindTable& builtin_kinds() {
  static const ConstraintKindTable table = ConstraintKindTable::builtin();
  return table;
}
KindFinder finder() {
  return [](const std::string& n) { return builtin_kinds().find(n); };
}

}  // namespace

TEST_CASE("per-frame IK: a position constraint is met exactly, other frames are untouched",
          "[per_frame_ik]") {
  const Motion leg = two_link_leg(20);
  ConstraintSet set;
  set.constraints.push_back(ankle_constraint("position", {0.1, 0.15, 0.3}, {{5}, {6}, {7}}));
  const PerFrameIkResult r = solve_per_frame_ik(leg, set, finder());
  CHECK(r.frames_constrained == 3);
  CHECK(r.frames_unmet == 0);
  CHECK(r.worst_violation < 1e-4);
  CHECK_THAT(r.message, Contains("met all constraints"));
  for (int f : {5, 6, 7}) CHECK((ankle_at(r.motion, f) - Eigen::Vector3d(0.1, 0.15, 0.3)).norm() < 1e-4);
  for (int f = 0; f < 20; ++f)
    if (f < 5 || f > 7) CHECK(r.motion.values.row(f) == leg.values.row(f));
  CHECK(r.iterations > 0);
  CHECK(r.seconds >= 0);
}

TEST_CASE("per-frame IK: inequality rows act only while violated (active set)", "[per_frame_ik]") {
  const Motion leg = two_link_leg(10);
  // The ankle is near y = 0.04 at rest bend; keep it above y = 0.2 (violated) at frame 3 and above
  // y = -1 (satisfied) at frame 4.
  const double inf = std::numeric_limits<double>::infinity();
  ConstraintSet set;
  set.constraints.push_back(ankle_constraint("region", {-inf, 0.2, -inf, inf, inf, inf}, {{3}}));
  set.constraints.push_back(ankle_constraint("region", {-inf, -1.0, -inf, inf, inf, inf}, {{4}}));
  const PerFrameIkResult r = solve_per_frame_ik(leg, set, finder());
  CHECK(r.frames_unmet == 0);
  // The active row holds at its bound (the damping wants no more change than needed).
  CHECK(ankle_at(r.motion, 3).y() == Approx(0.2).margin(1e-4));
  CHECK(ankle_at(r.motion, 3).y() >= 0.2 - 1e-4);
  // A satisfied inequality does not move the frame.
  CHECK((r.motion.values.row(4) - leg.values.row(4)).norm() < 1e-12);
}

TEST_CASE("per-frame IK: same_place is solved forward in time against the solved earlier frame",
          "[per_frame_ik]") {
  const Motion leg = two_link_leg(12);
  ConstraintSet set;
  // Where the ankle is at frame 2 (moved there by a position constraint) it must stay, on X and
  // Z only, through frame 6; the pairs chain [2,3], [3,4], ... as a non-skid plant does.
  set.constraints.push_back(ankle_constraint("position", {0.05, 0.1, 0.1}, {{2}}));
  set.constraints.push_back(ankle_constraint("same_place", {1, 0, 1}, {{2, 3}, {3, 4}, {4, 5}, {5, 6}}));
  const PerFrameIkResult r = solve_per_frame_ik(leg, set, finder());
  CHECK(r.frames_unmet == 0);
  const Eigen::Vector3d planted = ankle_at(r.motion, 2);
  CHECK((planted - Eigen::Vector3d(0.05, 0.1, 0.1)).norm() < 1e-4);
  for (int f = 3; f <= 6; ++f) {
    CAPTURE(f);
    CHECK(std::abs(ankle_at(r.motion, f).x() - planted.x()) < 1e-4);
    CHECK(std::abs(ankle_at(r.motion, f).z() - planted.z()) < 1e-4);
  }
  // The initial motion walks on: the plant was not met before solving.
  CHECK(std::abs(ankle_at(leg, 6).z() - planted.z()) > 0.05);
}

TEST_CASE("per-frame IK: unreachable constraints are reported, not hidden", "[per_frame_ik]") {
  const Motion leg = two_link_leg(10);
  ConstraintSet set;
  // Two position constraints on the same frame 30 cm apart: no pose meets both.
  set.constraints.push_back(ankle_constraint("position", {0.0, 0.1, 0.1}, {{4}}));
  set.constraints.push_back(ankle_constraint("position", {0.0, 0.1, 0.4}, {{4}}));
  const PerFrameIkResult r = solve_per_frame_ik(leg, set, finder());
  CHECK(r.frames_unmet == 1);
  CHECK(r.worst_violation == Approx(0.15).margin(2e-3));  // the least-squares compromise, halfway
  CHECK(r.worst_frame == 4);
  CHECK_THAT(r.message, Contains("unmet") && Contains("frame 4"));
}

TEST_CASE("per-frame IK: bad input is refused with the constraint's label", "[per_frame_ik]") {
  const Motion leg = two_link_leg(10);
  auto refuses = [&](Constraint c, const std::string& part) {
    ConstraintSet set;
    set.constraints.push_back(std::move(c));
    CHECK_THROWS_WITH(solve_per_frame_ik(leg, set, finder()), Contains(part));
  };
  Constraint unknown = ankle_constraint("position", {0, 0, 0}, {{1}});
  unknown.kind = "posiiton";
  refuses(unknown, "unknown constraint kind 'posiiton'");
  refuses(ankle_constraint("position", {0, 0, 0}, {{10}}), "frame 10 out of range");
  Constraint joint = ankle_constraint("position", {0, 0, 0}, {{1}});
  joint.points[0].joint = 7;
  refuses(joint, "joint 7 out of range");
  Constraint second = ankle_constraint("position", {0, 0, 0}, {{1}});
  second.points[0].character = 1;
  refuses(second, "names character 1");
  refuses(ankle_constraint("position", {0, 0}, {{1}}), "ankle position");  // the kind's own check
}

TEST_CASE("per-frame IK on a synthesized walk retargeted to shorter legs", "[per_frame_ik]") {
  synth::WalkOptions options;
  options.steps = 4;
  options.fps = 30;
  const synth::Synthesis walk = synth::synthesize_walk(options);
  // Target: thighs and shanks 85 %, the rest as it was; the initial estimate is the source motion.
  auto target = std::make_shared<motion::Skeleton>(*walk.figure.skeleton);
  for (synth::Side side : {synth::kLeft, synth::kRight}) {
    target->joint_mut(walk.figure.leg[side]).offset *= 0.85;
    target->joint_mut(walk.figure.foot[side]).offset *= 0.85;
  }
  Motion initial = walk.motion;
  initial.skeleton = target;
  ConstraintSet set;
  for (const synth::FootPlant& plant : walk.plants) {
    if (plant.point != synth::FootPoint::Heel && plant.point != synth::FootPoint::Toe) continue;
    Constraint c;
    c.kind = "position";
    c.label = plant.name();
    c.points = {{.joint = plant.joint, .local = plant.local}};
    c.params = {plant.world.x(), plant.world.y(), plant.world.z()};
    for (int f = plant.first_frame; f <= plant.last_frame; ++f) c.samples.push_back({.frames = {f}});
    set.constraints.push_back(std::move(c));
  }
  REQUIRE(set.constraints.size() >= 8);

  const PerFrameIkResult r = solve_per_frame_ik(initial, set, finder());
  INFO(r.message);
  CHECK(r.frames_unmet == 0);
  CHECK(r.worst_violation < 1e-4);
  CHECK(r.frames_constrained > initial.frame_count() / 2);
  // The metrics agree: plants held, no skate.
  const MetricsInputs in{
      .result = &r.motion, .constraints = &set, .kinds = &builtin_kinds(), .initial = &initial};
  const RetargetMetrics m = compute_metrics(in);
  CHECK(m.worst_violation_metres < 1e-4);
  CHECK(m.skate.worst < 1e-4);
  // Before solving, the shorter legs leave the feet in the air: a violation of centimetres.
  const RetargetMetrics before =
      compute_metrics({.result = &initial, .constraints = &set, .kinds = &builtin_kinds()});
  CHECK(before.worst_violation_metres > 0.05);
  // The snaps: the displacement from the initial estimate switches on and off from one frame to
  // the next, so a large part of its energy lies above what keys every 4 frames could carry.
  REQUIRE(m.energy);
  CAPTURE(m.energy->rotation.fraction, m.energy->translation.fraction);  // measured 0.146, 0.0077
  CHECK(m.energy->rotation.fraction > 0.05);
}

TEST_CASE("retarget.per_frame_ik node", "[per_frame_ik]") {
  const graph::Registry registry = test::registry_of(retarget_metrics_node_types());
  const Motion leg = two_link_leg(20);
  ConstraintSet set;
  set.constraints.push_back(ankle_constraint("position", {0.1, 0.15, 0.3}, {{5}, {6}}));
  const test::NodeContext ctx =
      test::run_node(registry, "retarget.per_frame_ik", test::params_for(registry, "retarget.per_frame_ik"),
                     {{"motion", graph::Value::make(leg)}, {"constraints", graph::Value::make(set)}});
  const Motion& out = ctx.outputs.at("motion").get<Motion>();
  CHECK((ankle_at(out, 5) - Eigen::Vector3d(0.1, 0.15, 0.3)).norm() < 1e-4);
  CHECK(std::get<std::int64_t>(ctx.figures.at("frames_unmet")) == 0);
  CHECK(std::get<double>(ctx.figures.at("worst_violation_mm")) < 0.1);
  CHECK(ctx.outputs.at("seconds").get<double>() >= 0);
}

// Real clips (CMU walks, BVH and ASF/AMC): footplants detected on the source (floor flavour:
// plant height plus non-skid, and above the floor everywhere), the figure and its root travel
// scaled to 60 % with the constraints' positions scaled alike; the source's own skate makes the
// non-skid rows violated before the solve. Per-frame IK meets every row on every frame.
TEST_CASE("per-frame IK on real walks scaled to 60 %", "[per_frame_ik]") {
  const std::string data = KG_DATA_DIR;
  struct Clip {
    std::string path, skeleton;
  };
  const std::vector<Clip> clips = {{data + "/cmu/bvh_motionbuilder/16_15.bvh", ""},
                                   {data + "/cmu/asf_amc/07_05.amc", data + "/cmu/asf_amc/07.asf"}};
  int read = 0;
  for (const Clip& clip : clips) {
    if (!std::filesystem::exists(clip.path) ||
        (!clip.skeleton.empty() && !std::filesystem::exists(clip.skeleton))) {
      WARN("skipped: " << clip.path << " not found");
      continue;
    }
    ++read;
    Motion source = io::import_motion(clip.path, clip.skeleton, io::ImportOptions{}).motion;
    if (source.fps > 60) source = motion::resample(source, 30.0);
    const double scale = 0.6;
    auto target = std::make_shared<motion::Skeleton>(*source.skeleton);
    for (int j = 0; j < target->joint_count(); ++j) {
      target->joint_mut(j).offset *= scale;
      for (Eigen::Vector3d& e : target->joint_mut(j).end_sites) e *= scale;
    }
    Motion initial = source;
    initial.skeleton = target;
    for (int c = 0; c < target->channel_count(); ++c)
      if (!motion::is_rotation(target->joint(target->channel_owner(c).first)
                                   .channels[static_cast<std::size_t>(target->channel_owner(c).second)]
                                   .kind))
        initial.values.col(c) *= scale;
    const motion::FootplantDetection detected = motion::detect_footplants(source, {});
    ConstraintSet set = footplant_constraints(detected, source.frame_count(),
                                              {.flavour = PlantFlavour::Floor, .above_floor = true});
    for (Constraint& c : set.constraints) {
      const std::size_t n = c.kind == "position" ? 3 : c.kind == "region" ? 6 : 0;
      auto scale_about_origin = [&](std::vector<double>& params) {
        for (std::size_t i = 0; i < n && i < params.size(); ++i)
          if (std::isfinite(params[i])) params[i] *= scale;
      };
      scale_about_origin(c.params);
      for (Sample& s : c.samples) scale_about_origin(s.params);
    }
    REQUIRE(!set.constraints.empty());
    const RetargetMetrics before =
        compute_metrics({.result = &initial, .constraints = &set, .kinds = &builtin_kinds()});

    const PerFrameIkResult r = solve_per_frame_ik(initial, set, finder());
    INFO(clip.path << ": " << source.frame_count() << " frames, " << set.constraints.size()
                   << " constraints; " << r.message << " in " << r.seconds << " s; skate before "
                   << before.skate.worst);
    CHECK(r.frames_unmet == 0);
    CHECK(r.worst_violation < 1e-4);
    const RetargetMetrics after = compute_metrics({.result = &r.motion,
                                                   .constraints = &set,
                                                   .kinds = &builtin_kinds(),
                                                   .source = &source,
                                                   .initial = &initial});
    CHECK(after.skate.worst < 2e-4);
    CHECK(after.skate.worst < before.skate.worst);
    CHECK(after.worst_violation_metres < 1e-4);
    REQUIRE(after.displacement_jerk.has_value());
    REQUIRE(after.energy.has_value());
    INFO("skate after " << after.skate.worst << ", displacement jerk " << after.displacement_jerk->rotation
                        << " rad/s^3, energy above fps/8: " << after.energy->rotation.fraction);
    CHECK(after.displacement_jerk->rotation > 0);
  }
  if (read == 0) WARN("skipped: no real clip found under " << data);
}
