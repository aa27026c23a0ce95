// The spacetime solver: the analytic Jacobian against finite differences, the active set, masks,
// two characters, a contradictory problem reported as such, densifying keys, and the 60% walk.
// Constraints are of the built-in kinds.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "kg/motion/kinematics.hpp"
#include "kg/numerics/banded_cholesky.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;
using motion::Channel;
using motion::ChannelKind;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The built-in kinds (constraint_kinds.hpp): position, region "above" a height, distance,
// same_place and parameter_range are what these tests need.
KindFinder builtin_kinds() {
  static const ConstraintKindTable table = ConstraintKindTable::builtin();
  return [](const std::string& name) { return table.find(name); };
}

// A three-segment arm hanging from a free root: 6 + 3 + 2 channels.
std::shared_ptr<const motion::Skeleton> make_arm(double scale = 1.0) {
  auto s = std::make_shared<motion::Skeleton>();
  const std::vector<Channel> zxy{
      {ChannelKind::Zrotation}, {ChannelKind::Xrotation}, {ChannelKind::Yrotation}};
  s->add_joint({.name = "root",
                .parent = -1,
                .channels = {{ChannelKind::Xposition},
                             {ChannelKind::Yposition},
                             {ChannelKind::Zposition},
                             {ChannelKind::Zrotation},
                             {ChannelKind::Xrotation},
                             {ChannelKind::Yrotation}},
                .end_sites = {}});
  s->add_joint({.name = "upper",
                .parent = 0,
                .offset = {0.1 * scale, -0.5 * scale, 0},
                .channels = zxy,
                .end_sites = {}});
  s->add_joint({.name = "lower",
                .parent = 1,
                .offset = {0, -0.4 * scale, 0},
                .channels = {{ChannelKind::Zrotation}, {ChannelKind::Xrotation}},
                .end_sites = {{0, -0.3 * scale, 0}}});
  return s;
}

// A smooth swinging motion of the arm at 30 fps.
motion::Motion swing(std::shared_ptr<const motion::Skeleton> s, int frames, double phase = 0) {
  motion::Motion m{s, motion::FrameMatrix::Zero(frames, s->channel_count()), 30.0, "swing"};
  for (int f = 0; f < frames; ++f) {
    const double t = f / 30.0;
    m.values(f, 0) = 0.2 * t;
    m.values(f, 1) = 1.2 + 0.02 * std::sin(3 * t + phase);
    m.values(f, 2) = 0.1 * t;
    m.values(f, 3) = 0.1 * std::sin(2 * t + phase);
    m.values(f, 6) = 0.5 * std::sin(4 * t + phase);
    m.values(f, 7) = 0.3 * std::cos(3 * t + phase);
    m.values(f, 8) = 0.2;
    m.values(f, 9) = 0.4 + 0.3 * std::sin(5 * t + phase);
    m.values(f, 10) = 0.1;
  }
  return m;
}

Eigen::Vector3d world_point(const motion::Motion& m, int frame, int joint, const Eigen::Vector3d& local) {
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
  motion::forward_kinematics(*m.skeleton, m.values.row(frame), world);
  return world[static_cast<std::size_t>(joint)] * local;
}

Constraint pin(const std::string& label, int joint, const Eigen::Vector3d& local, const Eigen::Vector3d& at,
               std::vector<int> frames, int character = 0) {
  Constraint c{.kind = "position",
               .label = label,
               .points = {{character, joint, local}},
               .params = {at.x(), at.y(), at.z()}};
  for (int f : frames) c.samples.push_back({{f}});
  return c;
}

const Eigen::Vector3d kHand{0, -0.3, 0};

}  // namespace

TEST_CASE("spacetime: analytic Jacobian of the whole problem matches finite differences", "[spacetime]") {
  const int frames = 13;
  auto arm = make_arm();
  auto arm2 = make_arm(0.8);
  SpacetimeProblem problem;
  std::vector<int> spacing(11, 3);
  spacing[6] = 2;  // mixed spacings
  spacing[9] = 1;
  problem.characters.push_back({.initial = swing(arm, frames), .frames_per_key = spacing});
  problem.characters.push_back({.initial = swing(arm2, frames, 0.7)});
  ConstraintSet set;
  set.constraints.push_back(pin("hand", 2, kHand, {0.3, 0.2, 0.1}, {2, 5, 12}));
  Constraint floor{.kind = "region",
                   .label = "elbow above",
                   .points = {{0, 1, {0, 0, 0}}},
                   .params = {-kInf, 0.9, -kInf, kInf, kInf, kInf}};
  for (int f = 0; f < frames; ++f) floor.samples.push_back({{f}});
  set.constraints.push_back(floor);
  Constraint gap{.kind = "distance",
                 .label = "hold",
                 .points = {{0, 2, kHand}, {1, 2, kHand}},
                 .params = {0.5},
                 .weight = 2};
  gap.samples.push_back({{4, 4}});
  gap.samples.push_back({{7, 9}});
  set.constraints.push_back(gap);
  Constraint stay{.kind = "same_place", .label = "plant", .points = {{1, 2, kHand}, {1, 2, kHand}}};
  stay.samples.push_back({{1, 11}});
  set.constraints.push_back(stay);
  Constraint range{
      .kind = "parameter_range", .label = "elbow limit", .channels = {{0, 9}}, .params = {0.0, 0.5}};
  for (int f = 0; f < frames; ++f) range.samples.push_back({{f}});
  set.constraints.push_back(range);
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;

  std::vector<DisplacementLayout> layouts = spacetime_layouts(problem);
  const int n = layouts[0].unknown_count() + layouts[1].unknown_count();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  const SpacetimeLinearization lin = linearize_spacetime(problem, x);
  REQUIRE(lin.jacobian.rows() == lin.residual.size());
  REQUIRE(lin.jacobian.cols() == n);
  REQUIRE(lin.residual.size() == 9 + 13 + 2 + 3 + 26);
  const double h = 1e-6;
  Eigen::MatrixXd fd(lin.jacobian.rows(), n);
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    fd.col(i) =
        (linearize_spacetime(problem, xp).residual - linearize_spacetime(problem, xm).residual) / (2 * h);
  }
  const double err = (fd - lin.jacobian).cwiseAbs().maxCoeff();
  INFO("max |J - J_fd| = " << err << ", max |J| = " << lin.jacobian.cwiseAbs().maxCoeff());
  CHECK(err < 1e-7);
  CHECK(lin.jacobian.cwiseAbs().maxCoeff() > 0.1);
  // Sparsity: a hand row at frame 2 touches only controls near frame 2.
  const int late = layouts[0].unknown(0, layouts[0].control_count(0) - 1);
  CHECK(lin.jacobian(0, late) == 0);
  CHECK(lin.jacobian(0, layouts[0].unknown(0, 0)) != 0);
}

TEST_CASE("spacetime: the active set takes violated inequality rows in and lets satisfied ones go",
          "[spacetime]") {
  const int frames = 30;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  ConstraintSet set;
  // Elbow height runs about 0.7 m: a floor at 0.5 is satisfied everywhere and must change nothing.
  Constraint low{.kind = "region",
                 .label = "low floor",
                 .points = {{0, 1, {0, 0, 0}}},
                 .params = {-kInf, 0.5, -kInf, kInf, kInf, kInf}};
  for (int f = 0; f < frames; ++f) low.samples.push_back({{f}});
  set.constraints.push_back(low);
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  SpacetimeResult r0 = solve_spacetime(problem);
  CHECK(r0.converged());
  CHECK(r0.iterations == 0);
  CHECK(r0.active_rows == 0);
  CHECK(r0.motions[0].values == m1.values);

  // The hand pinned 10 cm above a floor its elbow must stay over; the elbow starts below the
  // floor at the pinned frames (rows enter), ends above it (they leave).
  const double elbow_y = world_point(m1, 15, 1, Eigen::Vector3d::Zero()).y();
  Constraint high{.kind = "region",
                  .label = "high floor",
                  .points = {{0, 1, {0, 0, 0}}},
                  .params = {-kInf, elbow_y + 0.05, -kInf, kInf, kInf, kInf}};
  for (int f = 10; f <= 20; ++f) high.samples.push_back({{f}});
  set.constraints = {high};
  const Eigen::Vector3d hand = world_point(m1, 15, 2, kHand);
  set.constraints.push_back(pin("hand", 2, kHand, hand + Eigen::Vector3d(0, 0.25, 0), {15}));
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  REQUIRE(r.kinds.size() == 2);
  const KindReport& fl = r.kinds[1];  // sorted by name: position, region
  CHECK(fl.kind == "region");
  CHECK(fl.rows == 11);
  CHECK(fl.worst_inequality <= 1e-4);
  for (int f = 10; f <= 20; ++f)
    CHECK(world_point(r.motions[0], f, 1, Eigen::Vector3d::Zero()).y() >= elbow_y + 0.05 - 1e-4);
  // Raising the hand 25 cm lifts the elbow well clear at frame 15: that row has left the set.
  CHECK(world_point(r.motions[0], 15, 1, Eigen::Vector3d::Zero()).y() > elbow_y + 0.05 + 1e-3);
  CHECK(fl.active_rows < fl.rows);
  CHECK((world_point(r.motions[0], 15, 2, kHand) - hand - Eigen::Vector3d(0, 0.25, 0)).norm() < 1e-4);
}

TEST_CASE("spacetime: a mask freezes channels exactly", "[spacetime]") {
  const int frames = 25;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  ConstraintSet set;
  const Eigen::Vector3d hand = world_point(m1, 12, 2, kHand);
  set.constraints.push_back(pin("hand", 2, kHand, hand + Eigen::Vector3d(0.05, 0.1, -0.05), {12}));
  SpacetimeProblem problem;
  std::vector<bool> frozen(11, true);
  for (int c = 6; c <= 10; ++c) frozen[static_cast<std::size_t>(c)] = false;  // only the arm's joints move
  problem.characters.push_back({.initial = m1, .frozen = frozen});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  for (int c = 0; c < 6; ++c) CHECK(r.motions[0].values.col(c) == m1.values.col(c));
  CHECK((r.motions[0].values.rightCols(5) - m1.values.rightCols(5)).cwiseAbs().maxCoeff() > 0.01);
  CHECK((world_point(r.motions[0], 12, 2, kHand) - hand - Eigen::Vector3d(0.05, 0.1, -0.05)).norm() < 1e-4);
}

TEST_CASE("spacetime: two characters held a distance apart, one partly frozen", "[spacetime]") {
  const int frames = 40;
  auto a = make_arm();
  auto b = make_arm(0.7);
  motion::Motion ma = swing(a, frames);
  motion::Motion mb = swing(b, frames, 1.0);
  for (int f = 0; f < frames; ++f) mb.values(f, 0) += 0.6;  // side by side
  ConstraintSet set;
  Constraint hold{.kind = "distance",
                  .label = "hand-hold",
                  .points = {{0, 2, kHand}, {1, 2, kHand * 0.7}},
                  .params = {0.15}};
  for (int f = 5; f < 35; ++f) hold.samples.push_back({{f, f}});
  set.constraints.push_back(hold);
  SpacetimeProblem problem;
  std::vector<bool> frozen_b(11, false);
  for (int c = 0; c < 6; ++c) frozen_b[static_cast<std::size_t>(c)] = true;  // the second's root stays
  problem.characters.push_back({.initial = ma});
  problem.characters.push_back({.initial = mb, .frozen = frozen_b});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  REQUIRE(r.motions.size() == 2);
  for (int f = 5; f < 35; ++f) {
    const double d =
        (world_point(r.motions[0], f, 2, kHand) - world_point(r.motions[1], f, 2, kHand * 0.7)).norm();
    CHECK(d == Approx(0.15).margin(1e-4));
  }
  for (int c = 0; c < 6; ++c) CHECK(r.motions[1].values.col(c) == mb.values.col(c));
  // Both characters moved to meet.
  CHECK((r.motions[0].values - ma.values).cwiseAbs().maxCoeff() > 1e-3);
  CHECK((r.motions[1].values - mb.values).cwiseAbs().maxCoeff() > 1e-3);
}

TEST_CASE("spacetime: a contradictory problem is reported as not converged, with its violation",
          "[spacetime]") {
  const int frames = 20;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  const Eigen::Vector3d hand = world_point(m1, 10, 2, kHand);
  ConstraintSet set;
  set.constraints.push_back(pin("here", 2, kHand, hand, {10}));
  set.constraints.push_back(pin("there", 2, kHand, hand + Eigen::Vector3d(1.0, 0, 0), {10}));
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  problem.options.max_iterations = 15;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  CHECK_FALSE(r.converged());
  CHECK(r.status == SpacetimeStatus::NotConverged);
  CHECK(r.message.rfind("did not converge", 0) == 0);
  CHECK(r.message.find("'here'") != std::string::npos);
  CHECK(r.message.find("'there'") != std::string::npos);
  CHECK(r.message.find("frame 10") != std::string::npos);
  REQUIRE(r.violated.size() == 2);
  // The least-squares compromise: each pin missed by about half the metre.
  CHECK(r.violated[0].worst == Approx(0.5).margin(0.02));
  CHECK(r.worst_violation() == Approx(0.5).margin(0.02));
  CHECK(r.passes > 1);  // it tried denser keys before giving up
  CHECK(r.frames_per_key[0][0] == 1);
}

TEST_CASE("spacetime: denser keys on retry meet what the first spacing cannot", "[spacetime]") {
  const int frames = 33;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  // The hand must follow its own path shifted by 3 cm up and down every 2 frames: a frequency
  // far above what keys every 8 frames can carry, within reach of keys every 2.
  ConstraintSet set;
  Constraint zig{.kind = "position", .label = "zigzag", .points = {{0, 2, kHand}}, .params = {0, 0, 0}};
  for (int f = 0; f < frames; f += 2) {
    const Eigen::Vector3d p =
        world_point(m1, f, 2, kHand) + Eigen::Vector3d(0, (f / 2) % 2 ? 0.03 : -0.03, 0);
    zig.samples.push_back({{f}, {p.x(), p.y(), p.z()}});
  }
  set.constraints.push_back(zig);
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1, .frames_per_key = std::vector<int>(11, 8)});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  problem.options.densify = false;
  SpacetimeResult once = solve_spacetime(problem);
  CHECK_FALSE(once.converged());
  CHECK(once.passes == 1);
  CHECK(once.worst_violation() > 0.01);
  problem.options.densify = true;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  CHECK(r.converged());
  CHECK(r.passes >= 3);  // 8 -> 4 -> 2 (or 1)
  CHECK(r.frames_per_key[0][0] <= 2);
  CHECK(r.worst_violation() <= 1e-4);
}

TEST_CASE("spacetime: malformed problems throw with the constraint named", "[spacetime]") {
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, 10);
  ConstraintSet set;
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  auto message = [&]() -> std::string {
    try {
      solve_spacetime(problem);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  set.constraints = {pin("late", 2, kHand, {0, 0, 0}, {10})};
  CHECK_THAT(message(), Catch::Contains("'late'") && Catch::Contains("frame 10"));
  set.constraints = {pin("bad joint", 7, kHand, {0, 0, 0}, {1})};
  CHECK_THAT(message(), Catch::Contains("'bad joint'") && Catch::Contains("joint 7"));
  set.constraints = {pin("other", 2, kHand, {0, 0, 0}, {1}, 1)};
  CHECK_THAT(message(), Catch::Contains("'other'") && Catch::Contains("character 1"));
  Constraint unknown{.kind = "levitate", .label = "fly", .points = {{0, 2, kHand}}};
  unknown.samples.push_back({{1}});
  set.constraints = {unknown};
  CHECK_THAT(message(), Catch::Contains("'fly'") && Catch::Contains("unknown constraint kind 'levitate'"));
  set.constraints = {};
  problem.characters[0].frames_per_key = {4, 4};
  CHECK_THAT(message(), Catch::Contains("2 key spacings for 11 channels"));
  problem.characters[0].frames_per_key = {};
  problem.characters.push_back({.initial = swing(arm, 12)});
  CHECK_THAT(message(), Catch::Contains("12 frames"));
}

TEST_CASE("spacetime: a synthesized walk retargeted to 60% with short legs", "[spacetime][walk]") {
  synth::Synthesis walk = synth::synthesize_walk({.steps = 4, .speed = 1.3, .stature = 1.75, .fps = 30});
  const motion::Motion& src = walk.motion;
  const double scale = 0.6;
  // The target: 60% size, and thighs and shanks a further 15% shorter, so the scaled motion's
  // feet hang above the floor and slide: plants at the original positions scaled about the origin.
  auto target = std::make_shared<motion::Skeleton>(*src.skeleton);
  for (int j = 0; j < target->joint_count(); ++j) {
    motion::Joint& jt = target->joint_mut(j);
    double k = scale;
    for (int s = 0; s < 2; ++s)
      if (j == walk.figure.leg[static_cast<std::size_t>(s)] ||
          j == walk.figure.foot[static_cast<std::size_t>(s)])
        k *= 0.85;
    jt.offset *= k;
    for (Eigen::Vector3d& e : jt.end_sites) e *= scale;
  }
  motion::Motion m1{target, src.values, src.fps, "walk60"};
  m1.values.leftCols(3) *= scale;  // root translation scaled (§3.8); no re-centring here

  ConstraintSet set;
  for (const synth::FootPlant& p : walk.plants) {
    Constraint c = pin(p.name(), p.joint, p.local * scale, p.world * scale, {});
    for (int f = p.first_frame; f <= p.last_frame; ++f) c.samples.push_back({{f}});
    set.constraints.push_back(c);
  }
  for (int s = 0; s < 2; ++s)
    for (const auto& [joint, local] :
         {std::pair{walk.figure.foot[static_cast<std::size_t>(s)], walk.figure.heel_local},
          std::pair{walk.figure.toe[static_cast<std::size_t>(s)], walk.figure.toe_tip_local}}) {
      Constraint c{.kind = "region",
                   .label = "above floor",
                   .points = {{0, joint, local * scale}},
                   .params = {-kInf, 0.0, -kInf, kInf, kInf, kInf}};
      for (int f = 0; f < src.frame_count(); ++f) c.samples.push_back({{f}});
      set.constraints.push_back(c);
    }
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  // The scaled motion violates the plants by centimetres.
  problem.options.max_iterations = 0;
  problem.options.densify = false;
  const SpacetimeResult before = solve_spacetime(problem);
  CHECK(before.worst_violation() > 0.03);

  problem.options = {};
  const SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message << " (" << src.frame_count() << " frames, " << r.unknowns << " unknowns, bandwidth "
                 << r.bandwidth << ", " << r.seconds * 1000 << " ms)");
  REQUIRE(r.converged());
  CHECK(r.passes == 1);
  for (const KindReport& k : r.kinds) {
    CHECK(k.worst_equality <= 1e-3);
    CHECK(k.worst_inequality <= 1e-3);
  }
  // Checked independently of the solver's own report: FK of the result.
  double worst_plant = 0, lowest = 1;
  for (const synth::FootPlant& p : walk.plants)
    for (int f = p.first_frame; f <= p.last_frame; ++f)
      worst_plant = std::max(
          worst_plant, (world_point(r.motions[0], f, p.joint, p.local * scale) - p.world * scale).norm());
  for (int f = 0; f < src.frame_count(); ++f)
    for (int s = 0; s < 2; ++s)
      lowest = std::min(lowest, world_point(r.motions[0], f, walk.figure.toe[static_cast<std::size_t>(s)],
                                            walk.figure.toe_tip_local * scale)
                                    .y());
  CHECK(worst_plant <= 1e-3);
  CHECK(lowest >= -1e-3);
  // Smooth: the largest frame-to-frame change of any channel grows little over the source's.
  const auto step = [](const motion::FrameMatrix& v) {
    return (v.bottomRows(v.rows() - 1) - v.topRows(v.rows() - 1))
        .rightCols(v.cols() - 3)
        .cwiseAbs()
        .maxCoeff();
  };
  CHECK(step(r.motions[0].values) < 2 * step(src.values));
}

TEST_CASE("spacetime: banded Cholesky agrees with a dense factorisation", "[spacetime]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const auto& [n, b] : {std::pair{1, 0}, std::pair{7, 0}, std::pair{40, 5}, std::pair{25, 24}}) {
    numerics::BandedCholesky band;
    band.reset(n, b);
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - b); j < i; ++j) A(i, j) = A(j, i) = band.at(i, j) = 0.3 * u(rng);
      A(i, i) = band.at(i, i) = 0.3 * b + 1 + u(rng) * 0.1;
    }
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs[i] = u(rng);
    REQUIRE(band.factor());
    Eigen::VectorXd y = rhs;
    band.solve(y);
    CHECK((A * y - rhs).cwiseAbs().maxCoeff() < 1e-12);
  }
  numerics::BandedCholesky indefinite;
  indefinite.reset(2, 1);
  indefinite.at(0, 0) = 1;
  indefinite.at(1, 0) = 2;
  indefinite.at(1, 1) = 1;
  CHECK_FALSE(indefinite.factor());
}

TEST_CASE("spacetime: a two-frame row far apart (non-skid over a long span) is solved exactly",
          "[spacetime]") {
  const int frames = 40;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  ConstraintSet set;
  // The hand at frames 5, 10, ..., 35 must be where it is at frame 0: rows 35 frames apart
  // widen the band to span them.
  Constraint stay{.kind = "same_place", .label = "hand stays", .points = {{0, 2, kHand}, {0, 2, kHand}}};
  for (int f = 5; f < frames; f += 5) stay.samples.push_back({{0, f}});
  set.constraints.push_back(stay);
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = m1});
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  CHECK(r.bandwidth > 8 * 11);  // more than a few controls' worth of channels
  const Eigen::Vector3d p0 = world_point(r.motions[0], 0, 2, kHand);
  for (int f = 5; f < frames; f += 5) CHECK((world_point(r.motions[0], f, 2, kHand) - p0).norm() < 1e-5);
  // The place itself was free: it is not where the initial motion had it at frame 0 or 35 both.
  CHECK((world_point(m1, 35, 2, kHand) - world_point(m1, 0, 2, kHand)).norm() > 0.05);
}

TEST_CASE("spacetime: a morphing character is solved on each frame's own skeleton", "[spacetime]") {
  const int frames = 30;
  auto arm = make_arm();
  const motion::Motion m1 = swing(arm, frames);
  SpacetimeProblem problem;
  CharacterProblem cp{.initial = m1};
  for (int f = 0; f < frames; ++f) cp.skeleton_per_frame.push_back(make_arm(1.0 - 0.4 * f / (frames - 1)));
  problem.characters.push_back(cp);
  // The hand held still from frame 10 to 25 while the arm shrinks from 87% to 66%.
  const Eigen::Vector3d at = world_point(m1, 10, 2, kHand) + Eigen::Vector3d(0, 0.05, 0);
  ConstraintSet set;
  std::vector<int> held;
  for (int f = 10; f <= 25; ++f) held.push_back(f);
  set.constraints.push_back(pin("hold", 2, kHand, at, held));
  problem.constraints = &set;
  problem.kinds = builtin_kinds();
  problem.options.equality_tolerance = problem.options.inequality_tolerance = 1e-5;
  SpacetimeResult r = solve_spacetime(problem);
  INFO(r.message);
  REQUIRE(r.converged());
  for (int f = 10; f <= 25; ++f) {
    motion::Motion on_frame{cp.skeleton_per_frame[static_cast<std::size_t>(f)], r.motions[0].values, 30, ""};
    // The hand's point scales with the segment: the constraint's local point is fixed in the
    // joint frame, so measure the same local point on that frame's skeleton.
    CHECK((world_point(on_frame, f, 2, kHand) - at).norm() < 1e-5);
  }
  // Not the answer of the constant skeleton: the same solve without morphing ends elsewhere.
  problem.characters[0].skeleton_per_frame.clear();
  SpacetimeResult rigid = solve_spacetime(problem);
  REQUIRE(rigid.converged());
  CHECK((rigid.motions[0].values - r.motions[0].values).cwiseAbs().maxCoeff() > 1e-2);
  CHECK(r.motions[0].skeleton == m1.skeleton);
}
