// Per-frame IK baseline (per_frame_ik.hpp): Levenberg-Marquardt per frame, forward in time.
#include "kg/retarget/per_frame_ik.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <Eigen/Cholesky>

#include "kg/base/option_check.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retarget/constraint_kinds.hpp"

namespace kg::retarget {
namespace {

using motion::Motion;

struct SampleRef {
  const Constraint* constraint;
  const ConstraintKind* kind;
  const Sample* sample;
  int rows;
};

// Buffers reused over every frame and iteration (no allocation in the inner loop once sized).
struct Workspace {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> values;
  Eigen::VectorXd residual;
  Eigen::MatrixXd d_points, d_values;
  Eigen::Matrix<double, 3, Eigen::Dynamic> point_jacobian;
  std::vector<Eigen::Isometry3d> world;
};

// Everything one frame's rows need: the current q (frame f) and the solved frames before it.
class FrameProblem {
 public:
  FrameProblem(const motion::Skeleton& skeleton, const Motion& solved,
               const std::vector<std::vector<Eigen::Isometry3d>>& solved_world,
               std::vector<SampleRef> samples, int frame, Workspace& ws)
      : skeleton_(skeleton),
        solved_(solved),
        solved_world_(solved_world),
        samples_(std::move(samples)),
        frame_(frame),
        ws_(ws) {
    rows_ = 0;
    for (const SampleRef& s : samples_) rows_ += s.rows;
  }
  int rows() const { return rows_; }

  // The channels the rows can depend on: those moving a point read at this frame (the joint and
  // its ancestors) and the channels read at this frame. The others have a zero Jacobian column
  // and stay at q0 (their damping gradient is zero there), so the step is solved over these only.
  std::vector<int> unknown_channels() const {
    std::vector<bool> used(static_cast<std::size_t>(skeleton_.channel_count()), false);
    std::vector<bool> joint_done(static_cast<std::size_t>(skeleton_.joint_count()), false);
    for (const SampleRef& s : samples_) {
      const Constraint& c = *s.constraint;
      for (std::size_t i = 0; i < c.points.size(); ++i) {
        const int joint = c.points[i].joint;
        if (s.sample->frames[i] != frame_ || joint_done[static_cast<std::size_t>(joint)]) continue;
        joint_done[static_cast<std::size_t>(joint)] = true;
        for (int ch : motion::influencing_channels(skeleton_, joint))
          used[static_cast<std::size_t>(ch)] = true;
      }
      for (std::size_t i = 0; i < c.channels.size(); ++i)
        if (s.sample->frames[c.points.size() + i] == frame_)
          used[static_cast<std::size_t>(c.channels[i].channel)] = true;
    }
    std::vector<int> out;
    for (std::size_t ch = 0; ch < used.size(); ++ch)
      if (used[ch]) out.push_back(static_cast<int>(ch));
    return out;
  }

  // Residual (weighted, inequality rows clipped to min(r, 0)), worst violation (unweighted), and
  // when `jacobian` is set the Jacobian d(w rho)/dq (rows x channels; zero rows for inactive).
  void evaluate(const Eigen::RowVectorXd& q, Eigen::VectorXd& rho, double& worst, Eigen::MatrixXd* jacobian) {
    const int n = skeleton_.channel_count();
    ws_.world.resize(static_cast<std::size_t>(skeleton_.joint_count()));
    motion::forward_kinematics(skeleton_, q, ws_.world);
    rho.resize(rows_);
    if (jacobian) jacobian->setZero(rows_, n);
    worst = 0;
    int row0 = 0;
    for (const SampleRef& s : samples_) {
      const Constraint& c = *s.constraint;
      const std::size_t np = c.points.size(), nv = c.channels.size();
      ws_.points.resize(np);
      ws_.values.resize(nv);
      for (std::size_t i = 0; i < np; ++i) {
        const int f = s.sample->frames[i];
        const PointRef p = point_at(c, *s.sample, i);
        ws_.points[i] =
            f == frame_
                ? ws_.world[static_cast<std::size_t>(p.joint)] * p.local
                : solved_world_[static_cast<std::size_t>(f)][static_cast<std::size_t>(p.joint)] * p.local;
      }
      for (std::size_t i = 0; i < nv; ++i) {
        const int f = s.sample->frames[np + i];
        ws_.values[i] = f == frame_ ? q(c.channels[i].channel) : solved_.values(f, c.channels[i].channel);
      }
      ws_.residual.resize(s.rows);
      ws_.d_points.setZero(s.rows, static_cast<Eigen::Index>(3 * np));
      ws_.d_values.setZero(s.rows, static_cast<Eigen::Index>(nv));
      const std::span<const double> params = s.sample->params.empty()
                                                 ? std::span<const double>(c.params)
                                                 : std::span<const double>(s.sample->params);
      s.kind->evaluate(c, params, ws_.points, ws_.values, ws_.residual, ws_.d_points, ws_.d_values);
      for (int r = 0; r < s.rows; ++r) {
        const bool ineq = s.kind->is_inequality(c, r);
        const double value = ws_.residual(r);
        if (!c.soft) worst = std::max(worst, row_violation(value, ineq));
        const bool active = !ineq || value < 0;
        rho(row0 + r) = active ? c.weight * value : 0.0;
      }
      if (jacobian) {
        for (std::size_t i = 0; i < np; ++i) {
          if (s.sample->frames[i] != frame_) continue;
          const PointRef p = point_at(c, *s.sample, i);
          ws_.point_jacobian.setZero(3, n);
          motion::point_jacobian(skeleton_, q, ws_.world, p.joint, p.local, ws_.point_jacobian);
          jacobian->middleRows(row0, s.rows).noalias() +=
              ws_.d_points.middleCols(static_cast<Eigen::Index>(3 * i), 3) * ws_.point_jacobian;
        }
        for (std::size_t i = 0; i < nv; ++i) {
          if (s.sample->frames[np + i] != frame_) continue;
          jacobian->block(row0, c.channels[i].channel, s.rows, 1) +=
              ws_.d_values.col(static_cast<Eigen::Index>(i));
        }
        for (int r = 0; r < s.rows; ++r) {
          const bool active = !s.kind->is_inequality(c, r) || ws_.residual(r) < 0;
          if (active)
            jacobian->row(row0 + r) *= c.weight;
          else
            jacobian->row(row0 + r).setZero();
        }
      }
      row0 += s.rows;
    }
  }

 private:
  const motion::Skeleton& skeleton_;
  const Motion& solved_;
  const std::vector<std::vector<Eigen::Isometry3d>>& solved_world_;
  std::vector<SampleRef> samples_;
  int frame_;
  Workspace& ws_;
  int rows_ = 0;
};

std::string where(const Constraint& c) {
  return "constraint '" + c.label + "' (" + c.kind + ")";
}

// The references of `c` checked against the one character's skeleton.
void check_references(const Constraint& c, const motion::Skeleton& skeleton) {
  const int n = skeleton.channel_count();
  for (const PointRef& p : c.points) {
    if (p.character != 0)
      throw std::invalid_argument(where(c) +
                                  ": per-frame IK solves one character, the constraint names character " +
                                  std::to_string(p.character));
    if (p.joint < 0 || p.joint >= skeleton.joint_count())
      throw std::invalid_argument(where(c) + ": joint " + std::to_string(p.joint) +
                                  " out of range (skeleton has " + std::to_string(skeleton.joint_count()) +
                                  " joints)");
  }
  for (const ChannelRef& ch : c.channels) {
    if (ch.character != 0)
      throw std::invalid_argument(where(c) +
                                  ": per-frame IK solves one character, the constraint names character " +
                                  std::to_string(ch.character));
    if (ch.channel < 0 || ch.channel >= n)
      throw std::invalid_argument(where(c) + ": channel " + std::to_string(ch.channel) + " out of range (" +
                                  std::to_string(n) + " channels)");
  }
}

// Samples by the frame they belong to (the latest they read), checked on the way.
std::vector<std::vector<SampleRef>> samples_by_frame(const ConstraintSet& set, const KindFinder& kinds,
                                                     const motion::Skeleton& skeleton, int frames) {
  std::vector<std::vector<SampleRef>> by_frame(static_cast<std::size_t>(frames));
  for (const Constraint& c : set.constraints) {
    const ConstraintKind* kind = kinds ? kinds(c.kind) : nullptr;
    if (kind == nullptr) throw std::invalid_argument(where(c) + ": unknown constraint kind '" + c.kind + "'");
    kind->check(c);
    check_references(c, skeleton);
    const int rows = kind->rows(c);
    const std::size_t reads = c.points.size() + c.channels.size();
    for (const Sample& s : c.samples) {
      if (s.frames.size() != reads)
        throw std::invalid_argument(where(c) + ": a sample names " + std::to_string(s.frames.size()) +
                                    " frames, expected " + std::to_string(reads));
      int last = -1;
      for (int f : s.frames) {
        if (f < 0 || f >= frames)
          throw std::invalid_argument(where(c) + ": frame " + std::to_string(f) +
                                      " out of range (motion has " + std::to_string(frames) + " frames)");
        last = std::max(last, f);
      }
      if (last >= 0 && rows > 0) by_frame[static_cast<std::size_t>(last)].push_back({&c, kind, &s, rows});
    }
  }
  return by_frame;
}

// Levenberg-Marquardt on one frame's F_f (per_frame_ik.hpp), over the channels its rows can
// move. The buffers live over every frame (no allocation once sized).
class FrameSolver {
 public:
  FrameSolver(const motion::Skeleton& skeleton, const PerFrameIkOptions& options)
      : options_(options), m_(channel_sensitivity(skeleton)), eps_m_(options.epsilon * m_) {}

  // Solves the frame from `start`, damped toward q0; returns the iterations and leaves q() and
  // worst() (the worst unweighted violation of its rows at q).
  int solve(FrameProblem& problem, const Eigen::RowVectorXd& q0, const Eigen::RowVectorXd& start) {
    q0_ = q0;
    q_ = q0;
    select_unknowns(problem);
    // Only the frame's unknowns start warm: the other channels stay at q0 exactly.
    for (int c : cols_) q_(c) = start(c);
    lambda_ = 1e-4;
    problem.evaluate(q_, rho_, worst_, &jac_);
    value_ = objective(rho_, q_);
    int it = 0;
    for (; it < options_.max_iterations; ++it) {
      normal_equations();
      double step_metres = 0;
      if (!damped_step(problem, step_metres)) break;  // converged, or no step lowers F (a local minimum of F)
      problem.evaluate(q_, rho_, worst_, &jac_);
      if (worst_ <= options_.tolerance && step_metres < 1e-7) {
        ++it;
        break;
      }
    }
    return it;
  }
  const Eigen::RowVectorXd& q() const { return q_; }
  double worst() const { return worst_; }

 private:
  double objective(const Eigen::VectorXd& r, const Eigen::RowVectorXd& x) const {
    const Eigen::RowVectorXd d = x - q0_;
    return 0.5 * r.squaredNorm() + 0.5 * (d.array().square() * eps_m_.transpose().array()).sum();
  }

  // The frame's unknowns (FrameProblem::unknown_channels) and their eps M and M.
  void select_unknowns(const FrameProblem& problem) {
    cols_ = problem.unknown_channels();
    const Eigen::Index k = static_cast<Eigen::Index>(cols_.size());
    eps_s_.resize(k);
    m_s_.resize(k);
    for (Eigen::Index i = 0; i < k; ++i) {
      eps_s_(i) = eps_m_(cols_[static_cast<std::size_t>(i)]);
      m_s_(i) = m_(cols_[static_cast<std::size_t>(i)]);
    }
  }

  // J^T J + eps M and the gradient of F_f at q, over the unknowns.
  void normal_equations() {
    const Eigen::Index k = static_cast<Eigen::Index>(cols_.size());
    jac_s_.resize(jac_.rows(), k);
    for (Eigen::Index i = 0; i < k; ++i) jac_s_.col(i) = jac_.col(cols_[static_cast<std::size_t>(i)]);
    normal_.noalias() = jac_s_.transpose() * jac_s_;
    normal_.diagonal() += eps_s_;
    gradient_.noalias() = jac_s_.transpose() * rho_;
    for (Eigen::Index i = 0; i < k; ++i) {
      const int c = cols_[static_cast<std::size_t>(i)];
      gradient_(i) += eps_s_(i) * (q_(c) - q0_(c));
    }
    diag_ = normal_.diagonal();
  }

  // Levenberg-Marquardt's damped step: (normal + lambda D) step = -gradient, lambda shrunk after
  // a step that lowers F (taken), grown tenfold after one that does not (tried again), 12 tries.
  // False when no step was taken: the frame is met and at its minimum, or no step lowers F.
  bool damped_step(FrameProblem& problem, double& step_metres) {
    const Eigen::Index k = static_cast<Eigen::Index>(cols_.size());
    for (int attempt = 0; attempt < 12; ++attempt) {
      lm_ = normal_;
      lm_.diagonal() += lambda_ * diag_;
      ldlt_.compute(lm_);
      step_ = -ldlt_.solve(gradient_);
      step_metres = std::sqrt((step_.array().square() * m_s_.array()).sum());
      if (worst_ <= options_.tolerance && step_metres < 1e-7)
        return false;  // at the minimum, constraints met
      q_trial_ = q_;
      for (Eigen::Index i = 0; i < k; ++i) q_trial_(cols_[static_cast<std::size_t>(i)]) += step_(i);
      problem.evaluate(q_trial_, rho_trial_, worst_trial_, nullptr);
      const double trial = objective(rho_trial_, q_trial_);
      if (trial < value_) {
        q_ = q_trial_;
        value_ = trial;
        lambda_ = std::max(lambda_ * 0.3, 1e-9);
        return true;
      }
      lambda_ *= 10;
    }
    return false;
  }

  const PerFrameIkOptions& options_;
  const Eigen::VectorXd m_, eps_m_;
  std::vector<int> cols_;
  Eigen::VectorXd eps_s_, m_s_;
  Eigen::MatrixXd jac_, jac_s_, normal_, lm_;
  Eigen::VectorXd rho_, rho_trial_, gradient_, step_, diag_;
  Eigen::RowVectorXd q_, q0_, q_trial_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  double lambda_ = 0, value_ = 0, worst_ = 0, worst_trial_ = 0;
};

// The final violation of every row of the solved motion: the worst and the frame holding it.
void measure_violations(const ConstraintSet& set, const KindFinder& kinds, const Motion& out,
                        const std::vector<std::vector<Eigen::Isometry3d>>& solved_world, Workspace& ws,
                        PerFrameIkResult& result) {
  for (const Constraint& c : set.constraints) {
    if (c.soft) continue;
    const ConstraintKind* kind = kinds(c.kind);
    const int rows = kind->rows(c);
    const std::size_t np = c.points.size();
    ws.points.resize(np);
    ws.values.resize(c.channels.size());
    for (const Sample& s : c.samples) {
      for (std::size_t i = 0; i < np; ++i)
        ws.points[i] =
            solved_world[static_cast<std::size_t>(s.frames[i])][static_cast<std::size_t>(c.points[i].joint)] *
            point_at(c, s, i).local;
      for (std::size_t i = 0; i < c.channels.size(); ++i)
        ws.values[i] = out.values(s.frames[np + i], c.channels[i].channel);
      ws.residual.resize(rows);
      ws.d_points.setZero(rows, static_cast<Eigen::Index>(3 * np));
      ws.d_values.setZero(rows, static_cast<Eigen::Index>(c.channels.size()));
      const std::span<const double> params =
          s.params.empty() ? std::span<const double>(c.params) : std::span<const double>(s.params);
      kind->evaluate(c, params, ws.points, ws.values, ws.residual, ws.d_points, ws.d_values);
      for (int r = 0; r < rows; ++r) {
        const double v = row_violation(ws.residual(r), kind->is_inequality(c, r));
        if (v > result.worst_violation) {
          result.worst_violation = v;
          result.worst_frame = *std::max_element(s.frames.begin(), s.frames.end());
        }
      }
    }
  }
}

std::string outcome_message(const PerFrameIkResult& result, const std::vector<int>& unmet, double tolerance) {
  std::ostringstream msg;
  if (unmet.empty()) {
    msg << "met all constraints on " << result.frames_constrained << " constrained frames (worst violation "
        << result.worst_violation << ", " << result.iterations << " iterations)";
  } else {
    msg << "constraints unmet past tolerance " << tolerance << " on " << unmet.size() << " of "
        << result.frames_constrained << " constrained frames (first " << unmet.front() << ", last "
        << unmet.back() << "); worst violation " << result.worst_violation << " at frame "
        << result.worst_frame;
  }
  return msg.str();
}

}  // namespace

void PerFrameIkOptions::validate() const {
  using options::require;
  const char* o = "PerFrameIkOptions";
  require(options::non_negative(epsilon), o, "epsilon", epsilon, ">= 0 and finite");
  require(max_iterations >= 1, o, "max_iterations", max_iterations, ">= 1");
  require(options::non_negative(tolerance), o, "tolerance", tolerance, ">= 0 and finite (metres or radians)");
}

PerFrameIkResult solve_per_frame_ik(const Motion& initial, const ConstraintSet& set, const KindFinder& kinds,
                                    const PerFrameIkOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  initial.check();
  options.validate();
  const motion::Skeleton& skeleton = *initial.skeleton;
  const int frames = initial.frame_count();
  std::vector<std::vector<SampleRef>> by_frame = samples_by_frame(set, kinds, skeleton, frames);

  PerFrameIkResult result;
  result.motion = initial;
  Motion& out = result.motion;
  // World transforms of every solved frame (fixed points of multi-frame samples read them).
  std::vector<std::vector<Eigen::Isometry3d>> solved_world(static_cast<std::size_t>(frames));
  Workspace ws;
  FrameSolver solver(skeleton, options);
  std::vector<int> unmet;
  for (int f = 0; f < frames; ++f) {
    std::vector<SampleRef>& samples = by_frame[static_cast<std::size_t>(f)];
    if (!samples.empty()) {
      ++result.frames_constrained;
      FrameProblem problem(skeleton, out, solved_world, std::move(samples), f, ws);
      // Warm: the previous frame's solution moved as the initial motion moves between the two.
      const bool warm = options.warm_start && f > 0;
      const Eigen::RowVectorXd start_q =
          warm ? Eigen::RowVectorXd(out.values.row(f - 1) + initial.values.row(f) - initial.values.row(f - 1))
               : Eigen::RowVectorXd(initial.values.row(f));
      const int it = solver.solve(problem, initial.values.row(f), start_q);
      result.iterations += it;
      result.max_frame_iterations = std::max(result.max_frame_iterations, it);
      if (solver.worst() > options.tolerance) unmet.push_back(f);
      out.values.row(f) = solver.q();
    }
    solved_world[static_cast<std::size_t>(f)].resize(static_cast<std::size_t>(skeleton.joint_count()));
    motion::forward_kinematics(skeleton, out.values.row(f), solved_world[static_cast<std::size_t>(f)]);
  }
  measure_violations(set, kinds, out, solved_world, ws, result);
  result.frames_unmet = static_cast<int>(unmet.size());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.message = outcome_message(result, unmet, options.tolerance);
  return result;
}

}  // namespace kg::retarget
