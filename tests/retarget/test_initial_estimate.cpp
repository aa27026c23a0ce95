// retarget.initial_estimate: scaled root path, constraint displacements on the axes they fix,
// smoothness of the added shift, morph translation summation.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <limits>

#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/synth/synthesize.hpp"

using kg::retarget::Constraint;
using kg::retarget::ConstraintSet;
using kg::retarget::InitialEstimate;
using kg::retarget::Target;

namespace {

const kg::synth::Synthesis& walk30() {
  static const kg::synth::Synthesis w = kg::synth::synthesize_walk({.steps = 8, .speed = 1.3, .fps = 30});
  return w;
}

// Position constraints holding the heel and toe tip (points on the floor) at the source's
// footprints, every frame of their plants. The points are those of a character `scale` times
// the source's size (a point on a segment scales with it, as End Sites do).
ConstraintSet footprints(const kg::synth::Synthesis& w, std::array<double, 3> mask = {1, 1, 1},
                         double scale = 0.6) {
  ConstraintSet set;
  for (const kg::synth::FootPlant& p : w.plants) {
    if (p.point != kg::synth::FootPoint::Heel && p.point != kg::synth::FootPoint::Toe) continue;
    Constraint c;
    c.kind = "position";
    c.label = p.name() + " plant at " + std::to_string(p.first_frame);
    c.points = {{.character = 0, .joint = p.joint, .local = scale * p.local}};
    c.params = {p.world.x(), p.world.y(), p.world.z(), mask[0], mask[1], mask[2]};
    for (int f = p.first_frame; f <= p.last_frame; ++f) c.samples.push_back({.frames = {f}});
    set.constraints.push_back(std::move(c));
  }
  return set;
}

// Mean and worst distance of the heel and toe plants' points (on m's skeleton, `scale` times the
// source's size) from their footprints.
std::pair<double, double> plant_error(const kg::motion::Motion& m, const kg::synth::Synthesis& w,
                                      double scale = 0.6) {
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
  double sum = 0, worst = 0;
  int n = 0;
  for (const kg::synth::FootPlant& p : w.plants)
    for (int f = p.first_frame; f <= p.last_frame; ++f) {
      if (p.point != kg::synth::FootPoint::Heel && p.point != kg::synth::FootPoint::Toe) continue;
      kg::motion::forward_kinematics(*m.skeleton, m.values.row(f), world);
      const double d = (world[static_cast<std::size_t>(p.joint)] * (scale * p.local) - p.world).norm();
      sum += d;
      worst = std::max(worst, d);
      ++n;
    }
  return {sum / n, worst};
}

kg::retarget::KindFinder finder(const kg::retarget::ConstraintKindTable& table) {
  return [&table](const std::string& name) { return table.find(name); };
}

int root_x(const kg::motion::Skeleton& s) {
  return s.joint(0).first_channel;
}

}  // namespace

TEST_CASE("without constraints the root path is scaled and the motion moves to the target",
          "[retarget][initial]") {
  const auto& w = walk30();
  const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
  const InitialEstimate e = kg::retarget::initial_estimate(w.motion, t, nullptr, {});
  CHECK(e.motion.skeleton == t.skeleton);
  CHECK(e.motion.frame_count() == w.motion.frame_count());
  const int c0 = root_x(*w.motion.skeleton);
  for (int f = 0; f < w.motion.frame_count(); ++f) {
    for (int a = 0; a < 3; ++a)
      CHECK(e.motion.values(f, c0 + a) == Approx(0.6 * w.motion.values(f, c0 + a)).margin(1e-12));
    // Angles untouched.
    CHECK((e.motion.values.row(f).tail(w.motion.values.cols() - 3) -
           w.motion.values.row(f).tail(w.motion.values.cols() - 3))
              .cwiseAbs()
              .maxCoeff() == 0.0);
  }
  CHECK(e.shift.cwiseAbs().maxCoeff() == 0.0);
  CHECK(e.constrained_frames == 0);
}

TEST_CASE("footplant constraints pull the scaled walk back to its footprints, smoothly",
          "[retarget][initial]") {
  const auto& w = walk30();
  const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
  const ConstraintSet set = footprints(w);
  const auto table = kg::retarget::ConstraintKindTable::builtin();
  const InitialEstimate scaled = kg::retarget::initial_estimate(w.motion, t, nullptr, {});
  const InitialEstimate e = kg::retarget::initial_estimate(w.motion, t, &set, finder(table));

  const auto [before_mean, before_worst] = plant_error(scaled.motion, w);
  const auto [after_mean, after_worst] = plant_error(e.motion, w);
  WARN("plant error, scaled only: mean " << before_mean << " m, worst " << before_worst
                                         << " m; after the shift: mean " << after_mean << " m, worst "
                                         << after_worst << " m");
  CHECK(after_mean < 0.3 * before_mean);
  CHECK(after_worst < before_worst);
  CHECK(e.axes_fixed == std::array<bool, 3>{true, true, true});
  CHECK(e.rows_used > 0);

  // The root path is the scaled path plus the reported shift (the figure's file axes are world axes).
  const int c0 = root_x(*w.motion.skeleton);
  for (int f = 0; f < w.motion.frame_count(); ++f)
    for (int a = 0; a < 3; ++a)
      CHECK(e.motion.values(f, c0 + a) ==
            Approx(0.6 * w.motion.values(f, c0 + a) + e.shift(f, a)).margin(1e-12));

  // Uniform scaling about the floor keeps the feet on it: nothing to add vertically.
  CHECK(e.shift.col(1).cwiseAbs().maxCoeff() < 1e-6);
  // Smooth: second differences of the added shift stay small, far below the raw per-frame
  // displacements' (which jump from footprint to footprint).
  const Eigen::MatrixXd filled = kg::retarget::fill_gaps(e.raw_shift);
  double smooth = 0, raw = 0;
  for (int f = 1; f + 1 < e.shift.rows(); ++f) {
    smooth = std::max(smooth, (e.shift.row(f + 1) - 2 * e.shift.row(f) + e.shift.row(f - 1)).norm());
    raw = std::max(raw, (filled.row(f + 1) - 2 * filled.row(f) + filled.row(f - 1)).norm());
  }
  WARN("largest second difference of the shift: " << smooth << " m (unsmoothed " << raw << " m)");
  CHECK(smooth < 0.005);
  CHECK(smooth < 0.2 * raw);
}

TEST_CASE("only the axes constraints fix are shifted", "[retarget][initial]") {
  const auto& w = walk30();
  const auto table = kg::retarget::ConstraintKindTable::builtin();
  const int c0 = root_x(*w.motion.skeleton);

  SECTION("a horizontal mask leaves the height alone") {
    const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
    const ConstraintSet set = footprints(w, {1, 0, 1});
    const InitialEstimate e = kg::retarget::initial_estimate(w.motion, t, &set, finder(table));
    CHECK(e.axes_fixed == std::array<bool, 3>{true, false, true});
    CHECK(e.shift.col(1).cwiseAbs().maxCoeff() == 0.0);
    CHECK(e.shift.col(2).cwiseAbs().maxCoeff() > 0.1);  // the walk goes along +Z
  }
  SECTION("a floor the feet sink through pushes up, and only up") {
    // The source sunk 5 cm: its planted feet are below the floor.
    kg::motion::Motion sunk = w.motion;
    sunk.values.col(c0 + 1).array() -= 0.05;
    const Target t = kg::retarget::uniform_target(sunk.skeleton, 1.0);
    ConstraintSet set;
    const double inf = std::numeric_limits<double>::infinity();
    for (int side = 0; side < 2; ++side) {
      Constraint c;
      c.kind = "region";
      c.label = std::string(kg::synth::side_name(kg::synth::Side(side))) + " toe above the floor";
      c.points = {{.joint = w.figure.toe[static_cast<std::size_t>(side)], .local = w.figure.toe_tip_local}};
      c.params = {-inf, 0.0, -inf, inf, inf, inf};
      for (int f = 0; f < sunk.frame_count(); ++f) c.samples.push_back({.frames = {f}});
      set.constraints.push_back(std::move(c));
    }
    const InitialEstimate e = kg::retarget::initial_estimate(sunk, t, &set, finder(table));
    CHECK(e.axes_fixed == std::array<bool, 3>{false, true, false});
    CHECK(e.shift.col(0).cwiseAbs().maxCoeff() == 0.0);
    CHECK(e.shift.col(2).cwiseAbs().maxCoeff() == 0.0);
    // Mid-clip the push is the 5 cm the feet sank (toe tips on the floor while planted).
    const int mid = sunk.frame_count() / 2;
    CHECK(e.shift(mid, 1) == Approx(0.05).margin(0.005));
  }
  SECTION("same_place constraints fix no place") {
    const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
    ConstraintSet set;
    for (const kg::synth::FootPlant& p : w.plants) {
      Constraint c;
      c.kind = "same_place";
      c.label = p.name() + " no skid";
      c.points = {{.joint = p.joint, .local = p.local}, {.joint = p.joint, .local = p.local}};
      for (int f = p.first_frame + 1; f <= p.last_frame; ++f)
        c.samples.push_back({.frames = {p.first_frame, f}});
      set.constraints.push_back(std::move(c));
    }
    const InitialEstimate e = kg::retarget::initial_estimate(w.motion, t, &set, finder(table));
    CHECK(e.axes_fixed == std::array<bool, 3>{false, false, false});
    CHECK(e.shift.cwiseAbs().maxCoeff() == 0.0);
    CHECK(e.rows_used == 0);
    CHECK(e.rows_ignored > 0);
  }
  SECTION("errors name the constraint") {
    const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
    ConstraintSet set = footprints(w);
    set.constraints[0].samples.push_back({.frames = {100000}});
    CHECK_THROWS_WITH(kg::retarget::initial_estimate(w.motion, t, &set, finder(table)),
                      Catch::Contains(set.constraints[0].label) && Catch::Contains("frame 100000 outside"));
    set = footprints(w);
    set.constraints[1].kind = "teleport";
    CHECK_THROWS_WITH(kg::retarget::initial_estimate(w.motion, t, &set, finder(table)),
                      Catch::Contains("unknown constraint kind 'teleport'"));
  }
}

TEST_CASE("morphing: translation changes scaled by each frame's scale and summed", "[retarget][initial]") {
  const auto& w = walk30();
  const double end = w.motion.duration();
  const int n = w.motion.skeleton->joint_count();
  const Target t = kg::retarget::morph_target(
      w.motion.skeleton, {0.0, end}, {Eigen::VectorXd::Constant(n, 1.0), Eigen::VectorXd::Constant(n, 0.6)});
  const InitialEstimate e = kg::retarget::initial_estimate(w.motion, t, nullptr, {});
  const int c0 = root_x(*w.motion.skeleton);
  const int frames = w.motion.frame_count();
  REQUIRE(e.scale.size() == static_cast<std::size_t>(frames));
  CHECK(e.scale.front() == Approx(1.0));
  CHECK(e.scale.back() == Approx(0.6));
  for (int a = 0; a < 3; ++a) {
    double p = w.motion.values(0, c0 + a);  // s_0 = 1
    for (int f = 0; f < frames; ++f) {
      const double s = 1.0 + (0.6 - 1.0) * (f / w.motion.fps) / end;
      CHECK(e.scale[static_cast<std::size_t>(f)] == Approx(s).epsilon(1e-9));
      if (f > 0) p += s * (w.motion.values(f, c0 + a) - w.motion.values(f - 1, c0 + a));
      CHECK(e.motion.values(f, c0 + a) == Approx(p).margin(1e-9));
    }
  }
  // The forward travel is the integral of s dz: between what a constant 0.6 and 1.0 would give.
  const double z_src = w.motion.values(frames - 1, c0 + 2) - w.motion.values(0, c0 + 2);
  const double z_m1 = e.motion.values(frames - 1, c0 + 2) - e.motion.values(0, c0 + 2);
  CHECK(z_m1 < 0.999 * z_src);
  CHECK(z_m1 > 0.6 * z_src);
}

TEST_CASE("retarget.initial_estimate node", "[retarget][initial][node]") {
  const auto registry = kg::test::registry_of(kg::retarget_target_node_types());
  const auto& w = walk30();
  const Target t = kg::retarget::uniform_target(w.motion.skeleton, 0.6);
  auto ctx = kg::test::run_node(registry, "retarget.initial_estimate",
                                kg::test::params_for(registry, "retarget.initial_estimate"),
                                {{"motion", kg::graph::Value::make(w.motion)},
                                 {"target", kg::graph::Value::make(t)},
                                 {"constraints", kg::graph::Value::make(footprints(w, {1, 0, 1}))}});
  const auto& m1 = ctx.outputs.at("motion").get<kg::motion::Motion>();
  CHECK(m1.skeleton == t.skeleton);
  CHECK(std::get<double>(ctx.figures.at("scale")) == Approx(0.6));
  CHECK(std::get<double>(ctx.figures.at("max_shift_m")) > 0.1);
  CHECK(std::get<std::string>(ctx.figures.at("axes_fixed")) == "x z");

  // A target of another structure is refused.
  auto tiny = std::make_shared<kg::motion::Skeleton>();
  tiny->add_joint({.name = "root", .parent = -1});
  Target wrong = kg::retarget::uniform_target(tiny, 1.0);
  CHECK_THROWS_WITH(
      kg::test::run_node(
          registry, "retarget.initial_estimate", kg::test::params_for(registry, "retarget.initial_estimate"),
          {{"motion", kg::graph::Value::make(w.motion)}, {"target", kg::graph::Value::make(wrong)}}),
      Catch::Contains("target skeleton has 1 joints"));
}

TEST_CASE("a real walk on another subject's skeleton: planted feet pulled back on X and Z",
          "[retarget][initial][data]") {
  const std::filesystem::path dir = std::filesystem::path(KG_DATA_DIR) / "cmu/asf_amc";
  if (!std::filesystem::exists(dir / "16_15.amc") || !std::filesystem::exists(dir / "07.asf")) {
    WARN("skipped: CMU files not found under " << dir);
    return;
  }
  const auto in = kg::io::import_asf_amc((dir / "16.asf").string(), (dir / "16_15.amc").string(), {});
  const kg::motion::Motion m = kg::motion::resample(in.motion, 30.0);
  const auto& s = *m.skeleton;
  // Target: subject 7's proportions, then 0.6 of that (a child-sized subject 7).
  const Target seven = kg::retarget::load_target(m.skeleton, (dir / "07.asf").string()).target;
  const auto small =
      kg::retarget::scaled_skeleton(*seven.skeleton, Eigen::VectorXd::Constant(s.joint_count(), 0.6));
  const Target t = kg::retarget::skeleton_target(m.skeleton, *small, "0.6 x 07.asf");
  // Planted-looking frames: a foot's ankle within 2 cm of its lowest height in the clip.
  const Eigen::MatrixXd world = kg::motion::joint_world_positions(m);
  ConstraintSet set;
  for (const char* name : {"lfoot", "rfoot"}) {
    const int j = s.find_joint(name);
    REQUIRE(j >= 0);
    const double low = world.col(3 * j + 1).minCoeff();
    for (int fr = 0; fr < m.frame_count(); ++fr) {
      if (world(fr, 3 * j + 1) > low + 0.02) continue;
      Constraint c;
      c.kind = "position";
      c.label = std::string(name) + " at " + std::to_string(fr);
      c.points = {{.joint = j}};
      c.params = {world(fr, 3 * j), 0.0, world(fr, 3 * j + 2), 1, 0, 1};
      c.samples.push_back({.frames = {fr}});
      set.constraints.push_back(std::move(c));
    }
  }
  REQUIRE(set.constraints.size() > 20);
  const auto table = kg::retarget::ConstraintKindTable::builtin();
  const InitialEstimate scaled = kg::retarget::initial_estimate(m, t, nullptr, {});
  const InitialEstimate e = kg::retarget::initial_estimate(m, t, &set, finder(table));
  CHECK(e.scale.front() == Approx(0.6 * seven.overall_scale(0.0)).epsilon(1e-9));
  CHECK(e.axes_fixed == std::array<bool, 3>{true, false, true});
  auto error = [&](const kg::motion::Motion& mm) {
    const Eigen::MatrixXd w = kg::motion::joint_world_positions(mm);
    double sum = 0;
    for (const Constraint& c : set.constraints) {
      const int fr = c.samples[0].frames[0], j = c.points[0].joint;
      sum += std::hypot(w(fr, 3 * j) - c.params[0], w(fr, 3 * j + 2) - c.params[2]);
    }
    return sum / static_cast<double>(set.constraints.size());
  };
  const double before = error(scaled.motion), after = error(e.motion);
  WARN("16_15 on 0.6 x subject 7 (scale " << e.scale.front() << "): planted ankles " << before
                                          << " m from their "
                                          << "places when scaled, " << after << " m after the shift");
  CHECK(after < 0.5 * before);
  CHECK(e.shift.col(1).cwiseAbs().maxCoeff() == 0.0);
}
