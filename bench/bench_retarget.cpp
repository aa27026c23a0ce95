// Spacetime retargeting figures (issue 3): whole-solve time and worst violations of a walk
// retargeted to 60% size with shorter legs, footplants, floor and joint limits, at ~112 frames
// and at ~1,000 frames, on the synthesized walk (exact plants) and (when present) the captured
// walks CMU 16_15 and 07_05; the added jerk against the per-frame IK baseline; and the banded
// Cholesky against Eigen's sparse Cholesky on a normal matrix of the solve's shape. One thread.
//
//   bench_retarget [NAME]     (only the cases whose name contains NAME; KG_SPACETIME_TRACE=1
//                              prints every iteration)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/SparseCholesky>
#ifdef KG_HAVE_CERES
#include <ceres/ceres.h>
#endif

#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/numerics/banded_cholesky.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/footplants.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/per_frame_ik.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/retarget/target.hpp"
#include "kg/synth/synthesize.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The source skeleton scaled by `scale`, thighs and shanks (joints listed in `legs`) by `scale *
// legs_factor`.
std::shared_ptr<const motion::Skeleton> scaled(const motion::Skeleton& source, double scale,
                                               const std::vector<int>& legs = {}, double legs_factor = 1) {
  auto s = std::make_shared<motion::Skeleton>(source);
  for (int j = 0; j < s->joint_count(); ++j) {
    motion::Joint& jt = s->joint_mut(j);
    const bool leg = std::find(legs.begin(), legs.end(), j) != legs.end();
    jt.offset *= scale * (leg ? legs_factor : 1.0);
    for (Eigen::Vector3d& e : jt.end_sites) e *= scale;
  }
  return s;
}

// Position and region constraints scaled about the origin (points on segments scale too).
ConstraintSet scaled(ConstraintSet set, double s) {
  for (Constraint& c : set.constraints) {
    for (PointRef& p : c.points) p.local *= s;
    auto scale_params = [&](std::vector<double>& params) {
      if (c.kind == "position")
        for (std::size_t i = 0; i < 3 && i < params.size(); ++i) params[i] *= s;
      if (c.kind == "region")
        for (double& v : params)
          if (std::isfinite(v)) v *= s;
    };
    scale_params(c.params);
    for (Sample& sm : c.samples) scale_params(sm.params);
  }
  return set;
}

// Joint limits: every rotation channel within its range over the source clip widened by 10 degrees.
void add_joint_limits(ConstraintSet& set, const motion::Motion& source) {
  const motion::Skeleton& sk = *source.skeleton;
  for (int c = 0; c < sk.channel_count(); ++c) {
    const auto [j, k] = sk.channel_owner(c);
    if (!motion::is_rotation(sk.joint(j).channels[static_cast<std::size_t>(k)].kind)) continue;
    const double widen = 10 * M_PI / 180;
    Constraint lim{
        .kind = "parameter_range",
        .label = sk.channel_name(c) + " limit",
        .channels = {{0, c}},
        .params = {source.values.col(c).minCoeff() - widen, source.values.col(c).maxCoeff() + widen}};
    for (int f = 0; f < source.frame_count(); ++f) lim.samples.push_back({{f}});
    set.constraints.push_back(lim);
  }
}

struct Case {
  std::string name;
  motion::Motion m1;
  ConstraintSet set;
  std::vector<int> frames_per_key{};  // per channel; empty: 4 for all
};

const char* g_only = nullptr;  // argv[1]: run only the cases whose name contains it

void run(const Case& c, const ConstraintKindTable& table, int repeats) {
  if (g_only && c.name.find(g_only) == std::string::npos) return;
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = c.m1, .frames_per_key = c.frames_per_key});
  problem.constraints = &c.set;
  problem.kinds = [&](const std::string& n) { return table.find(n); };
  if (std::getenv("KG_SPACETIME_TRACE"))
    problem.options.trace = [](const std::string& l) { std::printf("    %s\n", l.c_str()); };
  const std::vector<motion::Motion> before{c.m1};
  const ViolationSummary v0 = summarize_violations(c.set, table, before);
  SpacetimeResult r;
  double best = 1e30;
  for (int i = 0; i < repeats; ++i) {
    const double t0 = now();
    r = solve_spacetime(problem);
    best = std::min(best, now() - t0);
  }
  std::printf("%s: %d frames, %d channels, %zu constraints, %d rows (%d active at the end), %d unknowns\n",
              c.name.c_str(), c.m1.frame_count(), c.m1.skeleton->channel_count(), c.set.constraints.size(),
              r.total_rows, r.active_rows, r.unknowns);
  std::printf("  before: worst violation %.2f cm (", v0.worst() * 100);
  for (const KindViolation& k : v0.kinds) std::printf(" %s %.2f", k.kind.c_str(), k.worst * 100);
  std::printf(" )\n");
  std::printf("  solve: %.1f ms (best of %d), %d iterations, %d pass(es), bandwidth %d, %s\n", best * 1000,
              repeats, r.iterations, r.passes, r.bandwidth, r.message.c_str());
  // Checked independently with the constraint library's own evaluation of the result.
  const ViolationSummary v = summarize_violations(c.set, table, r.motions);
  for (const KindViolation& k : v.kinds)
    std::printf("  %-16s rows %6d  worst %.4f mm  mean %.4f mm  violated(>1mm) %d\n", k.kind.c_str(), k.rows,
                k.worst * 1000, k.mean * 1000, k.violated_rows);

  // The smoothness figure: RMS jerk the adaptation adds, against the per-frame IK
  // baseline (Gleicher 1998, 3.1) on the same constraints from the same initial estimate.
  const PerFrameIkResult ik = solve_per_frame_ik(c.m1, c.set, problem.kinds);
  const JerkFigures added_st = rms_jerk_of_displacement(r.motions[0], c.m1);
  const JerkFigures added_ik = rms_jerk_of_displacement(ik.motion, c.m1);
  const double increase_st = rms_jerk(r.motions[0]).rotation - rms_jerk(c.m1).rotation;
  const double increase_ik = rms_jerk(ik.motion).rotation - rms_jerk(c.m1).rotation;
  std::printf("  per-frame IK: %.1f ms, worst violation %.4f mm\n", ik.seconds * 1000,
              ik.worst_violation * 1000);
  std::printf(
      "  jerk of the added displacement (rotations): spacetime %.1f rad/s^3, per-frame IK %.1f rad/s^3: "
      "ratio %.1f%% (target <= 20%%)\n",
      added_st.rotation, added_ik.rotation, 100 * added_st.rotation / std::max(added_ik.rotation, 1e-12));
  std::printf(
      "  RMS jerk increase over the initial motion (rotations): spacetime %+.1f, per-frame IK %+.1f "
      "rad/s^3\n",
      increase_st, increase_ik);
}

Case synth_case(int steps, double legs_factor, const char* name) {
  synth::Synthesis walk = synth::synthesize_walk({.steps = steps, .speed = 1.3, .stature = 1.75, .fps = 30});
  const double s = 0.6;
  std::vector<int> legs;
  for (int side = 0; side < 2; ++side) {
    legs.push_back(walk.figure.leg[static_cast<std::size_t>(side)]);
    legs.push_back(walk.figure.foot[static_cast<std::size_t>(side)]);
  }
  Case c;
  c.name = name;
  c.m1 = {scaled(*walk.motion.skeleton, s, legs, legs_factor), walk.motion.values, 30, "walk"};
  c.m1.values.leftCols(3) *= s;
  ConstraintSet set;
  for (const synth::FootPlant& p : walk.plants) {
    Constraint k{.kind = "position",
                 .label = p.name() + " plant " + std::to_string(p.first_frame),
                 .points = {{0, p.joint, p.local}},
                 .params = {p.world.x(), p.world.y(), p.world.z()}};
    for (int f = p.first_frame; f <= p.last_frame; ++f) k.samples.push_back({{f}});
    set.constraints.push_back(k);
  }
  for (int side = 0; side < 2; ++side) {
    for (const auto& [joint, local] :
         {std::pair{walk.figure.foot[static_cast<std::size_t>(side)], walk.figure.heel_local},
          std::pair{walk.figure.toe[static_cast<std::size_t>(side)], walk.figure.toe_tip_local}}) {
      Constraint k{.kind = "region",
                   .label = "above floor",
                   .points = {{0, joint, local}},
                   .params = {-kInf, 0.0, -kInf, kInf, kInf, kInf}};
      for (int f = 0; f < walk.motion.frame_count(); ++f) k.samples.push_back({{f}});
      set.constraints.push_back(k);
    }
  }
  c.set = scaled(set, s);
  add_joint_limits(c.set, walk.motion);
  return c;
}

// A captured walk retargeted the way graphs/retarget.yaml does it: footplants detected on the
// source (floor flavour, heights moved onto the target) with the floor, joint limits from the
// source's range widened by 10 degrees, moved onto a 60% target whose thighs and shanks are 51%
// (joints named as in CMU skeletons: the tibia and foot joints' offsets are thigh and shank),
// the initial estimate of §3.8 as m1 and the key spacing of §3.7 (Laplacian pyramid).
Case cmu_case(const motion::Motion& src, const char* name) {
  Eigen::VectorXd factors = Eigen::VectorXd::Constant(src.skeleton->joint_count(), 0.6);
  for (const char* leg : {"ltibia", "lfoot", "rtibia", "rfoot"}) {
    const int j = src.skeleton->find_joint(leg);
    if (j < 0) throw std::runtime_error(std::string("bench: no joint ") + leg + " in " + src.name);
    factors[j] = 0.6 * 0.85;
  }
  const Target target = factor_target(src.skeleton, factors);
  const motion::FootplantDetection d = motion::detect_footplants(src, {});
  PlantConstraintOptions plant_options{.flavour = PlantFlavour::Floor, .above_floor = true};
  plant_options.height_scale = plant_height_scale(target, src.fps);
  ConstraintSet set = footplant_constraints(d, src.frame_count(), plant_options);
  add_joint_limits(set, src);
  const ConstraintSet on_target = constraints_on_target(set, target);
  const ConstraintKindTable table = ConstraintKindTable::builtin();
  const KindFinder finder = [&](const std::string& k) { return table.find(k); };
  Case c;
  c.name = name;
  c.m1 = initial_estimate(src, target, &on_target, finder).motion;
  c.set = on_target;
  c.frames_per_key = choose_key_spacing(src, {}).frames_per_key;
  std::printf("  %s: %zu plants detected; keys every %d frames\n", name, d.plants.size(),
              c.frames_per_key.front());
  return c;
}

// Eigen's SimplicialLLT against the banded Cholesky on a random SPD matrix of the solve's shape.
void compare_linear_algebra(int n, int b) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  numerics::BandedCholesky band;
  band.reset(n, b);
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - b); j < i; ++j) {
      const double v = u(rng) * 0.1;
      band.at(i, j) = v;
      trip.emplace_back(i, j, v);
      trip.emplace_back(j, i, v);
    }
    band.at(i, i) = 0.1 * b + 1;
    trip.emplace_back(i, i, 0.1 * b + 1);
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::VectorXd rhs = Eigen::VectorXd::Ones(n);
  double t0 = now();
  if (!band.factor()) std::printf("banded factor failed\n");
  Eigen::VectorXd y = rhs;
  band.solve(y);
  const double t_band = now() - t0;
  t0 = now();
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt;
  llt.analyzePattern(A);
  const double t_analyze = now() - t0;
  t0 = now();
  llt.factorize(A);
  const Eigen::VectorXd z = llt.solve(rhs);
  const double t_llt = now() - t0;
  std::printf(
      "  n %d, bandwidth %d: banded Cholesky %.2f ms; SimplicialLLT %.2f ms (+ %.2f ms ordering); |diff| "
      "%.1e\n",
      n, b, t_band * 1000, t_llt * 1000, t_analyze * 1000, (y - z).cwiseAbs().maxCoeff());
}

#ifdef KG_HAVE_CERES
// One row of the problem linearised at x0: r(x) = r0 + sum over the control-time blocks it
// touches of J_b x_b (weighted, as the solver sees it).
class LinearRow final : public ceres::CostFunction {
 public:
  LinearRow(double r0, std::vector<Eigen::RowVectorXd> blocks) : r0_(r0), blocks_(std::move(blocks)) {
    set_num_residuals(1);
    for (const Eigen::RowVectorXd& b : blocks_)
      mutable_parameter_block_sizes()->push_back(static_cast<int>(b.size()));
  }
  bool Evaluate(double const* const* x, double* r, double** jacobians) const override {
    double v = r0_;
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      v += blocks_[b].dot(Eigen::Map<const Eigen::VectorXd>(x[b], blocks_[b].size()));
      if (jacobians && jacobians[b])
        Eigen::Map<Eigen::RowVectorXd>(jacobians[b], blocks_[b].size()) = blocks_[b];
    }
    r[0] = v;
    return true;
  }

 private:
  double r0_;
  std::vector<Eigen::RowVectorXd> blocks_;
};

// The damping sqrt(eps M) x of one control-time block.
class Damping final : public ceres::CostFunction {
 public:
  explicit Damping(Eigen::VectorXd scale) : scale_(std::move(scale)) {
    set_num_residuals(static_cast<int>(scale_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(scale_.size()));
  }
  bool Evaluate(double const* const* x, double* r, double** jacobians) const override {
    const auto n = scale_.size();
    Eigen::Map<Eigen::VectorXd>(r, n) = scale_.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(x[0], n));
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(jacobians[0], n,
                                                                                           n);
      J.setZero();
      J.diagonal() = scale_;
    }
    return true;
  }

 private:
  Eigen::VectorXd scale_;
};

// The issue asks which linear algebra serves best. Ceres' generic sparse normal Cholesky
// (SuiteSparse) on exactly the rows our first Gauss-Newton step solves (the problem linearised
// at the initial estimate, its active rows, the same damping), one thread, against our whole
// solve's time per iteration on the same problem. Ceres only solves here: its residuals are
// stored linear rows, so its figure is a lower bound on what a Ceres-based solver would take.
void compare_with_ceres(const Case& c, const ConstraintKindTable& table) {
  SpacetimeProblem problem;
  problem.characters.push_back({.initial = c.m1, .frames_per_key = c.frames_per_key});
  problem.constraints = &c.set;
  problem.kinds = [&](const std::string& n) { return table.find(n); };
  const DisplacementLayout layout = spacetime_layouts(problem).front();
  const int channels = c.m1.skeleton->channel_count();
  const int controls = layout.control_count(0);
  for (int ch = 1; ch < channels; ++ch)
    if (layout.control_count(ch) != controls) {
      std::printf("  (Ceres comparison needs one key spacing for all channels)\n");
      return;
    }
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(layout.unknown_count());
  const SpacetimeLinearization lin = linearize_spacetime(problem, x0);
  const Eigen::VectorXd sensitivity = channel_sensitivity(*c.m1.skeleton);
  const double epsilon = SpacetimeOptions{}.epsilon;
  SpacetimeResult ours;
  double best = 1e30;
  for (int i = 0; i < 3; ++i) {
    const double t0 = now();
    ours = solve_spacetime(problem);
    best = std::min(best, now() - t0);
  }
  std::printf(
      "  ours: %.1f ms per iteration over the whole solve (FK, analytic Jacobians, assembly, banded "
      "Cholesky, "
      "line search)\n",
      1000 * best / std::max(1, ours.iterations));
  // Parameter blocks of `width` channels at one control time: every channel (66: Ceres sees the
  // band's dense blocks) or one (Ceres sees every zero).
  for (const int width : {channels, 1}) {
    const int groups = (channels + width - 1) / width;
    std::vector<Eigen::VectorXd> x(static_cast<std::size_t>(controls * groups));
    auto block_of = [&](int control, int group) -> Eigen::VectorXd& {
      return x[static_cast<std::size_t>(control * groups + group)];
    };
    ceres::Problem ceres_problem;
    for (int b = 0; b < controls; ++b)
      for (int g = 0; g < groups; ++g) {
        const int first = g * width, n = std::min(width, channels - first);
        block_of(b, g) = Eigen::VectorXd::Zero(n);
        Eigen::VectorXd scale(n);
        for (int k = 0; k < n; ++k) scale[k] = std::sqrt(epsilon * sensitivity[first + k]);
        ceres_problem.AddResidualBlock(new Damping(scale), nullptr, block_of(b, g).data());
      }
    int rows = 0;
    for (Eigen::Index i = 0; i < lin.residual.size(); ++i) {
      if (lin.inequality[static_cast<std::size_t>(i)] && lin.residual[i] >= 0) continue;  // inactive
      std::vector<Eigen::RowVectorXd> row_blocks;
      std::vector<double*> params;
      for (int b = 0; b < controls; ++b)
        for (int g = 0; g < groups; ++g) {
          const int first = g * width, n = std::min(width, channels - first);
          Eigen::RowVectorXd jb(n);
          for (int k = 0; k < n; ++k) jb[k] = lin.jacobian(i, layout.unknown(first + k, b));
          if (jb.isZero(0)) continue;
          row_blocks.push_back(jb);
          params.push_back(block_of(b, g).data());
        }
      if (params.empty()) continue;
      ceres_problem.AddResidualBlock(new LinearRow(lin.residual[i], std::move(row_blocks)), nullptr, params);
      ++rows;
    }
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.num_threads = 1;
    options.max_num_iterations = 5;
    options.function_tolerance = options.gradient_tolerance = options.parameter_tolerance = 1e-16;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &ceres_problem, &summary);
    const int iterations = std::max<int>(1, static_cast<int>(summary.iterations.size()) - 1);
    std::printf(
        "  Ceres %s SPARSE_NORMAL_CHOLESKY (%s), 1 thread, %d active rows, %d unknowns in blocks of %d: "
        "%.1f ms per iteration (linear solver %.1f ms)\n",
        CERES_VERSION_STRING,
        summary.sparse_linear_algebra_library_type == ceres::SUITE_SPARSE ? "SuiteSparse" : "other", rows,
        layout.unknown_count(), width, 1000 * summary.minimizer_time_in_seconds / iterations,
        1000 * summary.linear_solver_time_in_seconds / iterations);
  }
}
#endif

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) g_only = argv[1];
  const ConstraintKindTable table = ConstraintKindTable::builtin();
  std::printf(
      "== synthesized walk, 30 Hz, to 60%% (thighs and shanks 51%%): fixed plants, floor, joint limits ==\n");
  // ~112 frames: 5 steps.
  const Case short_legs = synth_case(5, 0.85, "synth walk 60%, short legs");
  run(short_legs, table, 5);
#ifdef KG_HAVE_CERES
  if (!g_only) compare_with_ceres(short_legs, table);
#endif
  run(synth_case(5, 1.0, "synth walk 60% uniform (m1 already exact)"), table, 5);
  run(synth_case(56, 0.85, "synth walk 60%, short legs, long"), table, 2);

  const std::string walk_16_15 = std::string(KG_DATA_DIR) + "/cmu/bvh_motionbuilder/16_15.bvh";
  if (std::filesystem::exists(walk_16_15)) {
    std::printf(
        "== CMU 16_15 (walk, MotionBuilder BVH) at 30 Hz to 60%% (thighs and shanks 51%%): detected floor "
        "plants, floor, joint limits; the library's initial estimate ==\n");
    const motion::Motion src = motion::resample(io::import_motion(walk_16_15, "", {}).motion, 30.0);
    run(cmu_case(src, "16_15 60%, short legs"), table, 5);
  } else {
    std::printf("skipped CMU 16_15: %s not found\n", walk_16_15.c_str());
  }
  const std::string asf = std::string(KG_DATA_DIR) + "/cmu/asf_amc/07.asf";
  const std::string amc = std::string(KG_DATA_DIR) + "/cmu/asf_amc/07_05.amc";
  if (std::filesystem::exists(asf) && std::filesystem::exists(amc)) {
    std::printf(
        "== CMU 07_05 (slow walk) at 30 Hz to 60%% (thighs and shanks 51%%): detected floor plants, floor, "
        "joint limits; the library's initial estimate ==\n");
    io::ImportedMotion in = io::import_motion(amc, asf, {});
    const motion::Motion src = motion::resample(in.motion, 30.0);
    run(cmu_case(src, "07_05 60%, short legs"), table, 5);
    // 1,000 frames: the clip played forwards then backwards, repeated (a continuous motion).
    const int n = src.frame_count();
    const int frames = 1000;
    motion::Motion tiled{src.skeleton, motion::FrameMatrix(frames, src.values.cols()), 30, "07_05x"};
    for (int f = 0; f < frames; ++f) {
      const int period = 2 * (n - 1);
      const int p = f % period;
      tiled.values.row(f) = src.values.row(p < n ? p : period - p);
    }
    run(cmu_case(tiled, "07_05 60%, short legs, ~1000 frames (ping-pong)"), table, 2);
  } else {
    std::printf("skipped CMU 07_05: %s not found\n", amc.c_str());
  }

  if (g_only) return 0;
  std::printf("== linear algebra of one step ==\n");
  compare_linear_algebra(930, 120);
  compare_linear_algebra(1980, 270);
  compare_linear_algebra(8200, 120);
  return 0;
}
