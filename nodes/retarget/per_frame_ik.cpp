// Per-frame IK baseline (per_frame_ik.hpp): Levenberg-Marquardt per frame, forward in time.
#include "kg/retarget/per_frame_ik.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <Eigen/Cholesky>

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
        worst = std::max(worst, row_violation(value, ineq));
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

}  // namespace

PerFrameIkResult solve_per_frame_ik(const Motion& initial, const ConstraintSet& set, const KindFinder& kinds,
                                    const PerFrameIkOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  initial.check();
  if (!(options.epsilon >= 0) || options.max_iterations < 1 || !(options.tolerance >= 0))
    throw std::invalid_argument("per-frame IK: epsilon and tolerance must be >= 0 and max_iterations >= 1");
  const motion::Skeleton& skeleton = *initial.skeleton;
  const int frames = initial.frame_count();
  const int n = skeleton.channel_count();

  // Samples by the frame they belong to (the latest they read), checked on the way.
  std::vector<std::vector<SampleRef>> by_frame(static_cast<std::size_t>(frames));
  for (const Constraint& c : set.constraints) {
    const ConstraintKind* kind = kinds ? kinds(c.kind) : nullptr;
    if (kind == nullptr) throw std::invalid_argument(where(c) + ": unknown constraint kind '" + c.kind + "'");
    kind->check(c);
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

  PerFrameIkResult result;
  result.motion = initial;
  Motion& out = result.motion;
  const Eigen::VectorXd m = channel_sensitivity(skeleton);
  const Eigen::VectorXd eps_m = options.epsilon * m;

  // World transforms of every solved frame (fixed points of multi-frame samples read them).
  std::vector<std::vector<Eigen::Isometry3d>> solved_world(static_cast<std::size_t>(frames));
  Workspace ws;
  Eigen::MatrixXd jac, jac_s, normal, lm;
  Eigen::VectorXd rho, rho_trial, gradient, step, diag;
  Eigen::RowVectorXd q, q0, q_trial;
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
  std::vector<int> unmet;

  auto objective = [&](const Eigen::VectorXd& r, const Eigen::RowVectorXd& x) {
    const Eigen::RowVectorXd d = x - q0;
    return 0.5 * r.squaredNorm() + 0.5 * (d.array().square() * eps_m.transpose().array()).sum();
  };

  for (int f = 0; f < frames; ++f) {
    std::vector<SampleRef>& samples = by_frame[static_cast<std::size_t>(f)];
    if (!samples.empty()) {
      ++result.frames_constrained;
      FrameProblem problem(skeleton, out, solved_world, std::move(samples), f, ws);
      q0 = initial.values.row(f);
      q = q0;
      const std::vector<int> cols = problem.unknown_channels();
      const Eigen::Index k = static_cast<Eigen::Index>(cols.size());
      Eigen::VectorXd eps_s(k), m_s(k);
      for (Eigen::Index i = 0; i < k; ++i) {
        eps_s(i) = eps_m(cols[static_cast<std::size_t>(i)]);
        m_s(i) = m(cols[static_cast<std::size_t>(i)]);
      }
      double worst = 0, worst_trial = 0;
      double lambda = 1e-4;
      problem.evaluate(q, rho, worst, &jac);
      double value = objective(rho, q);
      int it = 0;
      for (; it < options.max_iterations; ++it) {
        jac_s.resize(jac.rows(), k);
        for (Eigen::Index i = 0; i < k; ++i) jac_s.col(i) = jac.col(cols[static_cast<std::size_t>(i)]);
        normal.noalias() = jac_s.transpose() * jac_s;
        normal.diagonal() += eps_s;
        gradient.noalias() = jac_s.transpose() * rho;
        for (Eigen::Index i = 0; i < k; ++i) {
          const int c = cols[static_cast<std::size_t>(i)];
          gradient(i) += eps_s(i) * (q(c) - q0(c));
        }
        diag = normal.diagonal();
        bool accepted = false;
        double step_metres = 0;
        for (int attempt = 0; attempt < 12 && !accepted; ++attempt) {
          lm = normal;
          lm.diagonal() += lambda * diag;
          ldlt.compute(lm);
          step = -ldlt.solve(gradient);
          step_metres = std::sqrt((step.array().square() * m_s.array()).sum());
          if (worst <= options.tolerance && step_metres < 1e-7) break;  // at the minimum, constraints met
          q_trial = q;
          for (Eigen::Index i = 0; i < k; ++i) q_trial(cols[static_cast<std::size_t>(i)]) += step(i);
          problem.evaluate(q_trial, rho_trial, worst_trial, nullptr);
          const double trial = objective(rho_trial, q_trial);
          if (trial < value) {
            accepted = true;
            q = q_trial;
            value = trial;
            lambda = std::max(lambda * 0.3, 1e-9);
          } else {
            lambda *= 10;
          }
        }
        if (!accepted) break;  // converged, or no step lowers F (a local minimum of F)
        problem.evaluate(q, rho, worst, &jac);
        if (worst <= options.tolerance && step_metres < 1e-7) {
          ++it;
          break;
        }
      }
      result.iterations += it;
      result.max_frame_iterations = std::max(result.max_frame_iterations, it);
      if (worst > options.tolerance) unmet.push_back(f);
      out.values.row(f) = q;
    }
    solved_world[static_cast<std::size_t>(f)].resize(static_cast<std::size_t>(skeleton.joint_count()));
    motion::forward_kinematics(skeleton, out.values.row(f), solved_world[static_cast<std::size_t>(f)]);
  }

  // The final violation of every row of the result.
  for (const Constraint& c : set.constraints) {
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

  result.frames_unmet = static_cast<int>(unmet.size());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ostringstream msg;
  if (unmet.empty()) {
    msg << "met all constraints on " << result.frames_constrained << " constrained frames (worst violation "
        << result.worst_violation << ", " << result.iterations << " iterations)";
  } else {
    msg << "constraints unmet past tolerance " << options.tolerance << " on " << unmet.size() << " of "
        << result.frames_constrained << " constrained frames (first " << unmet.front() << ", last "
        << unmet.back() << "); worst violation " << result.worst_violation << " at frame "
        << result.worst_frame;
  }
  result.message = msg.str();
  return result;
}

}  // namespace kg::retarget
