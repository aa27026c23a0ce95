// motion::Footplant detection against the synthesizer's exact plants and on real clips; footplant
// constraints in both flavours; the retarget.footplants node.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/footplants.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/target.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

// Detected plants of the point on (joint, local), in time order.
std::vector<motion::Footplant> plants_of(const motion::FootplantDetection& d, int joint,
                                         const Eigen::Vector3d& local) {
  std::vector<motion::Footplant> out;
  for (const motion::Footplant& p : d.plants) {
    const PointRef& r = d.points[static_cast<std::size_t>(p.point)].point;
    if (r.joint == joint && (r.local - local).norm() < 1e-9) out.push_back(p);
  }
  return out;
}

std::string describe(const motion::FootplantDetection& d) {
  std::ostringstream out;
  for (const motion::Footplant& p : d.plants)
    out << d.points[static_cast<std::size_t>(p.point)].name << " [" << p.first_frame << ", " << p.last_frame
        << "] skate " << p.skate * 1000 << " mm\n";
  return out.str();
}

// Compares detected plants of the ankle and toe-tip points with the synthesizer's, within
// `tolerance` frames at each end.
void compare_with_synthesizer(const synth::Synthesis& s, const motion::FootplantDetection& d, int tolerance) {
  int compared = 0;
  for (const synth::FootPlant& truth_first : s.plants) {
    if (truth_first.point != synth::FootPoint::Ankle && truth_first.point != synth::FootPoint::Toe) continue;
    // Do each (side, point) once.
    if (&truth_first != &*std::find_if(s.plants.begin(), s.plants.end(), [&](const synth::FootPlant& p) {
          return p.side == truth_first.side && p.point == truth_first.point;
        }))
      continue;
    std::vector<const synth::FootPlant*> truth;
    for (const synth::FootPlant& p : s.plants)
      if (p.side == truth_first.side && p.point == truth_first.point) truth.push_back(&p);
    const std::vector<motion::Footplant> found = plants_of(d, truth_first.joint, truth_first.local);
    INFO(truth_first.name() << ": synthesizer " << truth.size() << " plants, detected " << found.size()
                            << "\n"
                            << describe(d));
    REQUIRE(found.size() == truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
      INFO("plant " << i << ": synthesizer [" << truth[i]->first_frame << ", " << truth[i]->last_frame
                    << "], detected [" << found[i].first_frame << ", " << found[i].last_frame << "]");
      CHECK(std::abs(found[i].first_frame - truth[i]->first_frame) <= tolerance);
      CHECK(std::abs(found[i].last_frame - truth[i]->last_frame) <= tolerance);
      CHECK((found[i].mean - truth[i]->world).norm() < 0.01);
    }
    ++compared;
  }
  CHECK(compared == 4);  // ankle and toe tip of both feet
}

const std::string kData = KG_DATA_DIR;

}  // namespace

TEST_CASE("footplants of the synthesized walk match the synthesizer's plants") {
  for (double fps : {120.0, 30.0}) {
    INFO("fps " << fps);
    const synth::Synthesis walk =
        synth::synthesize_walk({.steps = 6, .speed = 1.3, .stature = 1.75, .fps = fps});
    const motion::FootplantDetection d = motion::detect_footplants(walk.motion, {});
    REQUIRE(d.points.size() == 4);
    CHECK(d.points[0].name == "LeftFoot");
    CHECK(d.points[1].name == "LeftToeBase/end");
    CHECK(d.points[3].name == "RightToeBase/end");
    CHECK(d.floor == Approx(0).margin(1e-6));  // the synthesizer's floor is y = 0
    // Within 0.1 s (3 frames at 30 Hz): a point leaving a plant accelerates from rest, so any
    // threshold sees it go a little late.
    compare_with_synthesizer(walk, d, static_cast<int>(std::lround(0.1 * fps)));
    for (const motion::Footplant& p : d.plants) CHECK(p.skate < 0.01);
  }
}

TEST_CASE("footplant options: named points, given floor, thresholds, minimum duration, errors") {
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 60});
  motion::FootplantOptions o;
  o.points = {"LeftToeBase/end", "RightFoot"};
  motion::FootplantDetection d = motion::detect_footplants(walk.motion, o);
  REQUIRE(d.points.size() == 2);
  CHECK(d.points[0].point.joint == walk.figure.toe[synth::kLeft]);
  CHECK((d.points[0].point.local - walk.figure.toe_tip_local).norm() < 1e-12);
  CHECK(d.points[1].point.joint == walk.figure.foot[synth::kRight]);
  const int toe_plants = d.count(0);

  // A heel: a point given in the foot's frame, compared with the synthesizer's heel plants.
  std::ostringstream heel;
  heel << "LeftFoot[" << walk.figure.heel_local.x() << " " << walk.figure.heel_local.y() << " "
       << walk.figure.heel_local.z() << "]";
  motion::FootplantOptions h;
  h.points = {heel.str()};
  const motion::FootplantDetection hd = motion::detect_footplants(walk.motion, h);
  REQUIRE(hd.points.size() == 1);
  CHECK((hd.points[0].point.local - walk.figure.heel_local).norm() < 1e-5);
  int heel_truth = 0;
  for (const synth::FootPlant& p : walk.plants)
    heel_truth += p.side == synth::kLeft && p.point == synth::FootPoint::Heel;
  CHECK(hd.count(0) == heel_truth);
  CHECK(toe_plants >= 2);

  // A floor given below every point: each point's rest level stays its own, so the same plants.
  o.floor = -1.0;
  d = motion::detect_footplants(walk.motion, o);
  CHECK(d.floor == -1.0);
  CHECK(d.count(0) == toe_plants);

  // Thresholds nothing exceeds and no trimming: the whole clip is one plant per point.
  o = {};
  o.speed_threshold = 100;
  o.height_threshold = 10;
  o.trim_distance = 0;
  d = motion::detect_footplants(walk.motion, o);
  REQUIRE(d.plants.size() == d.points.size());
  CHECK(d.plants[0].first_frame == 0);
  CHECK(d.plants[0].last_frame == walk.motion.frame_count() - 1);
  // Trimming keeps each plant's core within trim_distance of its median position.
  o.trim_distance = 0.05;
  d = motion::detect_footplants(walk.motion, o);
  for (const motion::Footplant& p : d.plants)
    CHECK(p.last_frame - p.first_frame + 1 < walk.motion.frame_count());
  o = {};
  o.min_duration_s = walk.motion.duration() + 1;
  CHECK(motion::detect_footplants(walk.motion, o).plants.empty());

  o = {};
  o.points = {"LeftToe"};
  CHECK_THROWS_WITH(motion::detect_footplants(walk.motion, o),
                    Catch::Contains("unknown joint 'LeftToe'") && Catch::Contains("nearest: 'LeftToeBase'"));
  o.points = {"LeftFoot[0 0.1]"};
  CHECK_THROWS_WITH(motion::detect_footplants(walk.motion, o), Catch::Contains("expected Joint[x y z]"));
  o.points = {"LeftFoot/end"};
  CHECK_THROWS_WITH(motion::detect_footplants(walk.motion, o), Catch::Contains("has no End Site"));
  o = {};
  o.hysteresis = 0.5;
  CHECK_THROWS_WITH(motion::detect_footplants(walk.motion, o), Catch::Contains("hysteresis"));
  o = {};
  o.height_threshold = 0;
  CHECK_THROWS_WITH(motion::detect_footplants(walk.motion, o),
                    Catch::Contains("FootplantOptions.height_threshold = 0.0"));

  // A skeleton without recognisable feet.
  auto sk = std::make_shared<motion::Skeleton>();
  sk->add_joint(
      {.name = "root", .parent = -1, .channels = {{motion::ChannelKind::Yposition}}, .end_sites = {}});
  motion::Motion blob{sk, motion::FrameMatrix::Zero(10, 1), 30.0, "blob"};
  CHECK_THROWS_WITH(motion::detect_footplants(blob, {}), Catch::Contains("no foot joint found"));
}

TEST_CASE("footplants: a lift shorter than bridge_s back to where it left is one plant") {
  // One foot point at 120 Hz: planted, lifted 6 cm (past height_threshold x hysteresis) for
  // `gap` frames, set down `moved` metres along X, planted again.
  auto clip = [](int gap, double moved) {
    auto sk = std::make_shared<motion::Skeleton>();
    sk->add_joint({.name = "root",
                   .parent = -1,
                   .channels = {{motion::ChannelKind::Xposition},
                                {motion::ChannelKind::Yposition},
                                {motion::ChannelKind::Zposition}},
                   .end_sites = {}});
    sk->add_joint({.name = "LeftFoot", .parent = 0, .channels = {}, .end_sites = {}});
    const int frames = 40 + gap + 40;
    motion::Motion m{sk, motion::FrameMatrix::Zero(frames, 3), 120.0, "lift"};
    for (int f = 40; f < 40 + gap; ++f) m.values(f, 1) = 0.06;
    for (int f = 40 + gap; f < frames; ++f) m.values(f, 0) = moved;
    return m;
  };
  motion::FootplantOptions o;
  o.points = {"LeftFoot"};
  o.trim_distance = 0;
  o.speed_threshold = 1000;  // heights alone decide here
  const motion::FootplantDetection jitter = motion::detect_footplants(clip(2, 0.004), o);
  INFO(describe(jitter));
  REQUIRE(jitter.plants.size() == 1);
  CHECK(jitter.plants[0].first_frame == 0);
  CHECK(jitter.plants[0].last_frame == 81);
  bool said = false;
  for (const std::string& note : jitter.notes)
    said = said || note.find("1 lift of at most 2 frames") != std::string::npos;
  CHECK(said);
  // Not bridged: bridging off, a lift as long as a step's swing, a foot set down elsewhere.
  o.bridge_s = 0;
  CHECK(motion::detect_footplants(clip(2, 0.004), o).plants.size() == 2);
  o = motion::FootplantOptions{.points = {"LeftFoot"}, .speed_threshold = 1000, .trim_distance = 0};
  CHECK(motion::detect_footplants(clip(24, 0.004), o).plants.size() == 2);
  CHECK(motion::detect_footplants(clip(2, 0.10), o).plants.size() == 2);
  o.bridge_distance = -1;
  CHECK_THROWS_WITH(motion::detect_footplants(clip(2, 0.004), o), Catch::Contains("bridge_distance"));
}

TEST_CASE("footplant constraints: fixed and floor flavours, above the floor") {
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 60});
  const motion::Motion& m = walk.motion;
  const motion::FootplantDetection d = motion::detect_footplants(m, {});
  REQUIRE(!d.plants.empty());
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();

  const ConstraintSet fixed = footplant_constraints(d, m.frame_count(), {.flavour = PlantFlavour::Fixed});
  REQUIRE(fixed.constraints.size() == d.plants.size());
  CHECK_NOTHROW(check_constraints(fixed, kinds));
  CHECK(fixed.constraints[0].kind == "position");
  CHECK(fixed.constraints[0].label ==
        d.points[static_cast<std::size_t>(d.plants[0].point)].name + " plant 1");
  CHECK(fixed.constraints[0].params.size() == 6);
  CHECK(static_cast<int>(fixed.constraints[0].samples.size()) ==
        d.plants[0].last_frame - d.plants[0].first_frame + 1);
  // The source meets its own plants to within its skate (the synthesizer's are exact: < 1 cm
  // since a detected plant may take in a frame of the roll).
  const std::span<const motion::Motion> chars(&m, 1);
  ViolationSummary v = summarize_violations(fixed, kinds, chars);
  CHECK(v.find("position")->worst < 0.01);

  const ConstraintSet floor =
      footplant_constraints(d, m.frame_count(), {.flavour = PlantFlavour::Floor, .above_floor = true});
  CHECK_NOTHROW(check_constraints(floor, kinds));
  int positions = 0, skids = 0, regions = 0;
  for (const Constraint& c : floor.constraints) {
    if (c.kind == "position") {
      ++positions;
      CHECK(c.params == std::vector<double>{0, c.params[1], 0, 0, 1, 0});
      CHECK(kinds.find("position")->rows(c) == 1);
    } else if (c.kind == "same_place") {
      ++skids;
      CHECK(c.params == std::vector<double>{1, 0, 1});
      CHECK(c.samples.front().frames[1] == c.samples.front().frames[0] + 1);
    } else if (c.kind == "region") {
      ++regions;
      CHECK(static_cast<int>(c.samples.size()) == m.frame_count());
      CHECK(c.params[1] == d.floor);
    }
  }
  CHECK(positions == static_cast<int>(d.plants.size()));
  CHECK(skids == static_cast<int>(d.plants.size()));  // every plant spans more than one frame
  CHECK(regions == static_cast<int>(d.points.size()));
  v = summarize_violations(floor, kinds, chars);
  CHECK(v.find("same_place")->worst < 0.005);  // per-frame horizontal travel during plants
  CHECK(v.find("region")->worst < 0.002);
}

TEST_CASE("footplant constraints on a target: heights above the floor scale, the source's floor is kept") {
  const ConstraintKindTable kinds = ConstraintKindTable::builtin();
  synth::Synthesis walk = synth::synthesize_walk({.steps = 3, .speed = 1.2, .stature = 1.75, .fps = 30});
  motion::Motion& m = walk.motion;
  // Lift the root by 5 cm: the floor is now at 0.05, a level the footplants must find and keep.
  const int root_y = 1;
  m.values.col(root_y).array() += 0.05;
  // And sink the first three frames by a further 4 cm: a captured floor that slopes away under
  // the estimate.
  m.values.block(0, root_y, 3, 1).array() -= 0.04;
  const motion::FootplantDetection d = motion::detect_footplants(m, {});
  REQUIRE(d.floor_estimated);
  REQUIRE(!d.plants.empty());
  const int frames = m.frame_count();

  SECTION("heights above the floor scale per frame, horizontal positions stay") {
    // A morph, and feet that shrink faster than toes.
    auto scale = [&](const PointRef& p, int f) {
      return (1.0 - 0.4 * f / (frames - 1.0)) * (p.local.isZero() ? 1.0 : 0.9);
    };
    const ConstraintSet fixed =
        footplant_constraints(d, frames, {.flavour = PlantFlavour::Fixed, .height_scale = scale});
    CHECK_NOTHROW(check_constraints(fixed, kinds));
    for (const Constraint& c : fixed.constraints) {
      const motion::Footplant& p = d.plants[static_cast<std::size_t>(&c - fixed.constraints.data())];
      REQUIRE(c.kind == "position");
      for (const Sample& s : c.samples) {
        const std::vector<double>& params = s.params.empty() ? c.params : s.params;
        const double sf = scale(c.points[0], s.frames[0]);
        CHECK(params[0] == p.mean.x());
        CHECK(params[2] == p.mean.z());
        CHECK(params[1] == Approx(d.floor + sf * (p.mean.y() - d.floor)).margin(1e-12));
      }
    }
    // A constant scale gives one set of params per plant.
    const ConstraintSet uniform = footplant_constraints(
        d, frames,
        {.flavour = PlantFlavour::Floor, .height_scale = [](const PointRef&, int) { return 0.6; }});
    for (const Constraint& c : uniform.constraints)
      if (c.kind == "position")
        for (const Sample& s : c.samples) CHECK(s.params.empty());
  }

  SECTION("an estimated floor never lifts a point above its source height; a given floor holds everywhere") {
    const ConstraintSet set =
        footplant_constraints(d, frames, {.flavour = PlantFlavour::Floor, .above_floor = true});
    const std::span<const motion::Motion> chars(&m, 1);
    const ViolationSummary v = summarize_violations(set, kinds, chars);
    CHECK(v.find("region")->worst == 0.0);
    int lowered = 0;
    for (const Constraint& c : set.constraints)
      if (c.kind == "region")
        for (const Sample& s : c.samples) {
          const std::vector<double>& params = s.params.empty() ? c.params : s.params;
          CHECK(params[1] <= d.floor);
          if (params[1] < d.floor - 0.01) {
            ++lowered;
            CHECK(s.frames[0] < 3);
          }
        }
    CHECK(lowered >= 2);  // at least the two ankles in the sunk frames

    motion::FootplantOptions given;
    given.floor = d.floor;
    const motion::FootplantDetection dg = motion::detect_footplants(m, given);
    CHECK(!dg.floor_estimated);
    const ConstraintSet level =
        footplant_constraints(dg, frames, {.flavour = PlantFlavour::Floor, .above_floor = true});
    for (const Constraint& c : level.constraints)
      if (c.kind == "region") {
        CHECK(c.params[1] == d.floor);
        for (const Sample& s : c.samples) CHECK(s.params.empty());
      }
    CHECK(summarize_violations(level, kinds, chars).find("region")->worst > 0.02);
  }

  SECTION("a height scale that is not positive is refused") {
    CHECK_THROWS_WITH(
        footplant_constraints(d, frames, {.height_scale = [](const PointRef&, int) { return -1.0; }}),
        Catch::Contains("expected > 0"));
    CHECK_THROWS_WITH(
        footplant_constraints(d, frames, {.height_scale = [](const PointRef&, int) { return NAN; }}),
        Catch::Contains("expected > 0"));
  }
}

TEST_CASE("height_factor: a foot point rests on the segments below it") {
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 2, .speed = 1.2, .stature = 1.75, .fps = 30});
  const motion::Skeleton& s = *walk.motion.skeleton;
  // Thighs and shanks (the offsets of LeftLeg and LeftFoot) at 0.5, feet and toes at 0.8, the rest 0.6.
  Eigen::VectorXd factors = Eigen::VectorXd::Constant(s.joint_count(), 0.6);
  for (const char* j : {"LeftLeg", "LeftFoot", "RightLeg", "RightFoot"}) factors[s.find_joint(j)] = 0.5;
  for (const char* j : {"LeftToeBase", "RightToeBase"}) factors[s.find_joint(j)] = 0.8;
  const Target target = factor_target(walk.motion.skeleton, factors);
  const int ankle = s.find_joint("LeftFoot"), toe = s.find_joint("LeftToeBase");
  // The ankle stands on the foot (LeftToeBase's offset) and the toes (its End Site): 0.8, not the
  // shank's 0.5 nor the body's.
  CHECK(height_factor(target, {0, ankle, Eigen::Vector3d::Zero()}, 0) == Approx(0.8));
  CHECK(height_factor(target, {0, toe, s.joint(toe).end_sites.front()}, 0) == Approx(0.8));
  // A heel offset on the foot joint weighs in the foot joint's own factor.
  const double heel = height_factor(target, {0, ankle, Eigen::Vector3d(0, -0.07, -0.05)}, 0);
  CHECK(heel < 0.8);
  CHECK(heel > 0.5);
  // Nothing below: the overall scale.
  const int head = s.find_joint("Head");
  if (s.joint(head).end_sites.empty())
    CHECK(height_factor(target, {0, head, Eigen::Vector3d::Zero()}, 0) == Approx(target.overall_scale(0)));
  CHECK_THROWS(height_factor(target, {0, 999, Eigen::Vector3d::Zero()}, 0));
}

TEST_CASE("footplants on real walks: plausible plant counts per foot") {
  struct Clip {
    std::string path, skeleton;
  };
  const std::vector<Clip> clips = {{kData + "/cmu/bvh_motionbuilder/16_15.bvh", ""},
                                   {kData + "/cmu/asf_amc/07_05.amc", kData + "/cmu/asf_amc/07.asf"},
                                   {kData + "/other_skeletons/games105/walk60.bvh", ""}};
  int read = 0;
  for (const Clip& clip : clips) {
    if (!std::filesystem::exists(clip.path)) {
      WARN("skipped: " << clip.path << " not found");
      continue;
    }
    const motion::Motion m = io::import_motion(clip.path, clip.skeleton, io::ImportOptions{}).motion;
    ++read;
    const motion::FootplantDetection d = motion::detect_footplants(m, {});
    INFO(clip.path << ": " << m.frame_count() << " frames at " << m.fps << " Hz\n" << describe(d));
    for (const std::string& n : d.notes) INFO(n);
    REQUIRE(d.points.size() >= 2);
    // A walk plants each foot about once per stride (~1 s); allow 0.4 to 1.6 per second, at least 1.
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      const int n = d.count(static_cast<int>(i));
      INFO(d.points[i].name << ": " << n << " plants in " << m.duration() << " s");
      CHECK(n >= 1);
      CHECK(n <= std::max(2.0, 1.6 * m.duration()));
      CHECK(n >= std::floor(0.4 * m.duration()));
    }
    for (const motion::Footplant& p : d.plants) CHECK(p.skate < 0.05);
    // A walk's pace is below the walk-run transition: no threshold follows the body.
    for (const std::string& n : d.notes) CHECK(n.find("the body runs") == std::string::npos);
  }
  if (read == 0) WARN("skipped: no real clip found under " << kData);
}

TEST_CASE("footplants on real runs: every foot planted in stance, the body's pace said") {
  struct Clip {
    std::string path, skeleton;
  };
  const std::vector<Clip> clips = {{kData + "/cmu/bvh_daz/09_06.bvh", ""},
                                   {kData + "/cmu/bvh_daz/02_03.bvh", ""},
                                   {kData + "/cmu/asf_amc/09_06.amc", kData + "/cmu/asf_amc/09.asf"},
                                   {kData + "/cmu/bvh_iclone_cc_rig/002_03.bvh", ""},
                                   {kData + "/other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh", ""},
                                   {kData + "/other_skeletons/games105/run_forward.bvh", ""}};
  int read = 0;
  std::size_t plants_with = 0, plants_without = 0;
  for (const Clip& clip : clips) {
    if (!std::filesystem::exists(clip.path)) {
      WARN("skipped: " << clip.path << " not found");
      continue;
    }
    const motion::Motion m = io::import_motion(clip.path, clip.skeleton, io::ImportOptions{}).motion;
    ++read;
    const motion::FootplantDetection d = motion::detect_footplants(m, {});
    std::string notes;
    for (const std::string& n : d.notes) notes += n + "\n";
    INFO(clip.path << ": " << m.frame_count() << " frames at " << m.fps << " Hz\n" << describe(d) << notes);
    CHECK_THAT(notes, Catch::Contains("the body runs"));
    // Each foot (a point of it) is planted at least once, and no more often than a stance per
    // 0.25 s: a run's stride is 0.6 to 0.8 s, one stance per foot.
    for (const bool left : {true, false}) {
      int planted = 0;
      for (std::size_t i = 0; i < d.points.size(); ++i) {
        const std::string& name = d.points[i].name;
        const bool is_left = name.find('l') == 0 || name.find("_L") != std::string::npos ||
                             name.find("Left") != std::string::npos;
        if (is_left == left) planted = std::max(planted, d.count(static_cast<int>(i)));
      }
      CHECK(planted >= 1);
      CHECK(planted <= std::max(1.0, std::ceil(m.duration() / 0.25)));
    }
    // A stance is short, and a planted point rolls a few centimetres in it, not a stride.
    for (const motion::Footplant& p : d.plants) {
      CHECK((p.last_frame - p.first_frame + 1) / m.fps <= 0.4);
      CHECK(p.skate < 0.15);
    }
    // A static root joint at the origin above the figure (the Bandai layout) changes no plant:
    // joints that never move are not the body.
    motion::Skeleton rooted;
    rooted.add_joint({.name = "static_root", .parent = -1});
    for (int j = 0; j < m.skeleton->joint_count(); ++j) {
      motion::Joint joint = m.skeleton->joint(j);
      joint.parent = joint.parent < 0 ? 0 : joint.parent + 1;
      rooted.add_joint(joint);
    }
    rooted.file_to_world = m.skeleton->file_to_world;
    rooted.source_unit_metres = m.skeleton->source_unit_metres;
    motion::Motion with_root = m;
    with_root.skeleton = std::make_shared<const motion::Skeleton>(std::move(rooted));
    const motion::FootplantDetection r = motion::detect_footplants(with_root, {});
    REQUIRE(r.plants.size() == d.plants.size());
    for (std::size_t k = 0; k < d.plants.size(); ++k) {
      CHECK(r.plants[k].first_frame == d.plants[k].first_frame);
      CHECK(r.plants[k].last_frame == d.plants[k].last_frame);
    }
    // Without the body's pace, noisy stances are missed (the reason for the criterion); a clean
    // capture (GAMES-105) has its plants either way.
    motion::FootplantOptions still;
    still.body_relative = 0;
    const std::size_t without = motion::detect_footplants(m, still).plants.size();
    CHECK(without <= d.plants.size());
    plants_without += without;
    plants_with += d.plants.size();
  }
  if (read == 0) WARN("skipped: no real clip found under " << kData);
  if (read == static_cast<int>(clips.size())) CHECK(plants_with >= 2 * plants_without);
}

TEST_CASE("retarget.footplants node") {
  const graph::Registry registry = test::registry_of(retarget_constraint_node_types());
  const synth::Synthesis walk =
      synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 60});
  test::NodeContext ctx =
      test::run_node(registry, "retarget.footplants",
                     test::params_for(registry, "retarget.footplants",
                                      {{"flavour", std::string("floor")}, {"above_floor", true}}),
                     {{"motion", graph::Value::make(walk.motion)}});
  const ConstraintSet& set = ctx.outputs.at("constraints").get<ConstraintSet>();
  CHECK(!set.constraints.empty());
  CHECK(std::get<std::int64_t>(ctx.figures.at("plants.LeftToeBase/end")) >= 2);
  CHECK(std::get<double>(ctx.figures.at("floor_m")) == Approx(0).margin(1e-6));
  CHECK(ctx.logged("points (auto): LeftFoot, LeftToeBase/end, RightFoot, RightToeBase/end"));
  CHECK(std::get<std::string>(ctx.figures.at("kinds")).find("same_place") != std::string::npos);

  // With a target connected, plant heights are the target's: a 60% figure's toe tip rests lower.
  const ConstraintSet& source_set = set;
  test::NodeContext small =
      test::run_node(registry, "retarget.footplants", test::params_for(registry, "retarget.footplants", {}),
                     {{"motion", graph::Value::make(walk.motion)},
                      {"target", graph::Value::make(uniform_target(walk.motion.skeleton, 0.6))}});
  const ConstraintSet& small_set = small.outputs.at("constraints").get<ConstraintSet>();
  CHECK(std::get<double>(small.figures.at("height_scale.LeftFoot")) == Approx(0.6));
  CHECK(std::get<double>(small.figures.at("height_scale.LeftToeBase/end")) == Approx(0.6));
  REQUIRE(!small_set.constraints.empty());
  const double floor = std::get<double>(small.figures.at("floor_m"));
  for (const Constraint& c : small_set.constraints) {
    const auto original =
        std::find_if(source_set.constraints.begin(), source_set.constraints.end(),
                     [&](const Constraint& o) { return o.label == c.label && o.kind == "position"; });
    if (c.kind != "position" || original == source_set.constraints.end()) continue;
    CHECK(c.params[1] - floor == Approx(0.6 * (original->params[1] - floor)).margin(1e-12));
  }

  // Named points and a given floor; a bad floor text fails when the node is built.
  ctx = test::run_node(registry, "retarget.footplants",
                       test::params_for(registry, "retarget.footplants",
                                        {{"points", std::string("LeftToeBase/end, RightToeBase/end")},
                                         {"floor", std::string("0.0")}}),
                       {{"motion", graph::Value::make(walk.motion)}});
  CHECK(ctx.figures.count("plants.LeftFoot") == 0);
  CHECK(std::get<double>(ctx.figures.at("floor_m")) == 0.0);
  CHECK_THROWS_WITH(
      test::run_node(registry, "retarget.footplants",
                     test::params_for(registry, "retarget.footplants", {{"floor", std::string("low")}}),
                     {{"motion", graph::Value::make(walk.motion)}}),
      Catch::Contains("floor 'low'"));
}

TEST_CASE(
    "a point that rests at its floor level but gets no plant is a warning with the numbers, and strict "
    "fails") {
  // Issue 14: runs got 0 plants and nothing said so. The synthesized walk with its body drifting
  // sideways at 0.4 m/s (a capture whose feet slide, or a run's rolling stance): no plant.
  synth::Synthesis walk = synth::synthesize_walk({.steps = 4, .speed = 1.2, .stature = 1.75, .fps = 60});
  const motion::FootplantDetection honest = motion::detect_footplants(walk.motion, {});
  CHECK(!honest.plants.empty());
  CHECK(honest.warnings.empty());
  REQUIRE(walk.motion.skeleton->joint(0).channels[0].kind == motion::ChannelKind::Xposition);
  motion::Motion fast = walk.motion;
  for (int f = 0; f < fast.frame_count(); ++f) fast.values(f, 0) += 0.4 * f / fast.fps;
  const motion::FootplantDetection d = motion::detect_footplants(fast, {});
  INFO(describe(d));
  CHECK(d.plants.empty());
  REQUIRE(d.warnings.size() == d.points.size());
  CHECK_THAT(d.warnings[1],
             Catch::StartsWith("LeftToeBase/end gets no plant although it stays within 3 cm of its "
                               "rest level for "));
  CHECK_THAT(d.warnings[1], Catch::Contains("fps): its horizontal speed there is 0.4 to ") &&
                                Catch::Contains("below its speed threshold 0.15 m/s"));
  // A speed threshold above the slide gives the plants back, and no warning.
  const motion::FootplantDetection scaled =
      motion::detect_footplants(fast, {.speed_threshold = 0.5, .trim_distance = 0});
  CHECK(scaled.plants.size() >= honest.plants.size() - 2);
  CHECK(scaled.warnings.empty());

  const graph::Registry registry = test::registry_of(retarget_constraint_node_types());
  test::NodeContext ctx =
      test::run_node(registry, "retarget.footplants", test::params_for(registry, "retarget.footplants", {}),
                     {{"motion", graph::Value::make(fast)}});
  CHECK(std::get<std::int64_t>(ctx.figures.at("points_without_plants")) == 4);
  CHECK(ctx.logged("warning: LeftFoot gets no plant although"));
  CHECK_THROWS_WITH(
      test::run_node(registry, "retarget.footplants",
                     test::params_for(registry, "retarget.footplants", {{"strict", true}}),
                     {{"motion", graph::Value::make(fast)}}),
      Catch::Contains("LeftFoot gets no plant although") &&
          Catch::Contains("(and 3 more point(s)); strict: no plant on a point that touches the floor"));
}
