// The initial estimate m1 (§3.8, step 2 of §4); see initial_estimate.hpp for each step.
#include "kg/retarget/initial_estimate.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "kg/motion/kinematics.hpp"

namespace kg::retarget {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string label_of(const Constraint& c) {
  return "constraint '" + (c.label.empty() ? c.kind : c.label) + "'";
}

// The world axis a derivative row lies along, or -1.
int single_axis(const Eigen::Vector3d& g) {
  const double n = g.cwiseAbs().maxCoeff();
  if (!(n > 0)) return -1;
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(g[a]) <= 1e-9 * n) continue;
    if (axis >= 0) return -1;
    axis = a;
  }
  return axis;
}

}  // namespace

motion::Motion scale_translation(const motion::Motion& source, const Target& target,
                                 std::vector<double>* scales) {
  const motion::Skeleton& s = *source.skeleton;
  motion::Motion out = source;
  const int frames = source.frame_count();
  std::vector<double> scale(static_cast<std::size_t>(frames));
  std::vector<Eigen::VectorXd> factors;
  const Eigen::VectorXd constant_factors = target.morphing() ? Eigen::VectorXd() : target.joint_factors(0.0);
  const double constant_scale = target.morphing() ? 0.0 : target.overall_scale(0.0);
  for (int f = 0; f < frames; ++f)
    scale[static_cast<std::size_t>(f)] =
        target.morphing() ? target.overall_scale(f / source.fps) : constant_scale;

  for (int j = 0; j < s.joint_count(); ++j) {
    const motion::Joint& jt = s.joint(j);
    for (std::size_t c = 0; c < jt.channels.size(); ++c) {
      if (motion::is_rotation(jt.channels[c].kind)) continue;
      const int col = jt.first_channel + static_cast<int>(c);
      if (jt.parent < 0) {
        // Root translation: per-frame changes scaled by that frame's scale and summed (§5).
        double acc = 0;
        for (int f = 0; f < frames; ++f) {
          const double sf = scale[static_cast<std::size_t>(f)];
          acc = f == 0 ? sf * source.values(0, col)
                       : acc + sf * (source.values(f, col) - source.values(f - 1, col));
          out.values(f, col) = acc;
        }
      } else {
        // An offset given as a channel: the joint's own length factor.
        for (int f = 0; f < frames; ++f) {
          const double factor =
              target.morphing() ? target.joint_factors(f / source.fps)[j] : constant_factors[j];
          out.values(f, col) = factor * source.values(f, col);
        }
      }
    }
  }
  if (scales != nullptr) *scales = std::move(scale);
  return out;
}

namespace {

// Per frame and axis: sums and counts of the equality rows' displacements, and the violated
// inequality rows' pushes (largest positive, most negative, sum, count).
struct Displacements {
  explicit Displacements(int frames)
      : eq_sum(Eigen::MatrixXd::Zero(frames, 3)),
        eq_n(Eigen::MatrixXd::Zero(frames, 3)),
        in_max(Eigen::MatrixXd::Zero(frames, 3)),
        in_min(Eigen::MatrixXd::Zero(frames, 3)),
        in_sum(Eigen::MatrixXd::Zero(frames, 3)),
        in_n(Eigen::MatrixXd::Zero(frames, 3)) {}

  // The rows of one sample at frame f (residuals r, d r / d points dp): each row fixing a
  // single world axis gives the displacement along it that meets the row.
  void add_rows(const Constraint& c, const ConstraintKind& kind, int f, const Eigen::VectorXd& r,
                const Eigen::MatrixXd& dp) {
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (std::size_t p = 0; p < c.points.size(); ++p)
        g += dp.block<1, 3>(i, 3 * static_cast<Eigen::Index>(p)).transpose();
      const int a = single_axis(g);
      if (a < 0 || !std::isfinite(r[i])) {
        ++ignored;
        continue;
      }
      const double d = -r[i] / g[a];
      if (!kind.is_inequality(c, static_cast<int>(i))) {
        eq_sum(f, a) += d;
        eq_n(f, a) += 1;
        ++used;
      } else if (r[i] < 0) {
        in_max(f, a) = std::max(in_max(f, a), d);
        in_min(f, a) = std::min(in_min(f, a), d);
        in_sum(f, a) += d;
        in_n(f, a) += 1;
        ++used;
      }
    }
  }

  // Per frame and axis: the equality rows' mean, else the pushes (of one sign: the largest
  // satisfies them all; of both signs: their mean), else NaN.
  Eigen::MatrixXd resolve() const {
    const Eigen::Index frames = eq_sum.rows();
    Eigen::MatrixXd out = Eigen::MatrixXd::Constant(frames, 3, kNaN);
    for (Eigen::Index f = 0; f < frames; ++f)
      for (int a = 0; a < 3; ++a) {
        if (eq_n(f, a) > 0) {
          out(f, a) = eq_sum(f, a) / eq_n(f, a);
        } else if (in_n(f, a) > 0) {
          if (in_min(f, a) >= 0)
            out(f, a) = in_max(f, a);
          else if (in_max(f, a) <= 0)
            out(f, a) = in_min(f, a);
          else
            out(f, a) = in_sum(f, a) / in_n(f, a);
        }
      }
    return out;
  }

  Eigen::MatrixXd eq_sum, eq_n, in_max, in_min, in_sum, in_n;
  int used = 0, ignored = 0;
};

// The sample's frames checked against the motion; whether they are one instant.
bool one_instant(const Constraint& c, const Sample& sample, int frames) {
  if (sample.frames.size() != c.points.size())
    throw std::invalid_argument(label_of(c) + ": a sample has " + std::to_string(sample.frames.size()) +
                                " frames for " + std::to_string(c.points.size()) + " points");
  const int f = sample.frames.front();
  bool one = true;
  for (int sf : sample.frames) {
    if (sf < 0 || sf >= frames)
      throw std::invalid_argument(label_of(c) + ": frame " + std::to_string(sf) + " outside the motion (0.." +
                                  std::to_string(frames - 1) + ")");
    one = one && sf == f;
  }
  return one;
}

}  // namespace

Eigen::MatrixXd constraint_displacements(const motion::Motion& scaled, const Target& target,
                                         const ConstraintSet& constraints, const KindFinder& kinds,
                                         int* rows_used, int* rows_ignored) {
  const int frames = scaled.frame_count();
  const int joints = scaled.skeleton->joint_count();
  Displacements acc(frames);

  // FK of the frames constraints read, on the target (per frame when morphing), computed once.
  std::vector<std::vector<Eigen::Isometry3d>> world(static_cast<std::size_t>(frames));
  auto pose = [&](int f) -> const std::vector<Eigen::Isometry3d>& {
    std::vector<Eigen::Isometry3d>& w = world[static_cast<std::size_t>(f)];
    if (w.empty()) {
      w.resize(static_cast<std::size_t>(joints));
      const std::shared_ptr<const motion::Skeleton> sk = target.skeleton_at(f / scaled.fps);
      motion::forward_kinematics(*sk, scaled.values.row(f), w);
    }
    return w;
  };

  std::vector<Eigen::Vector3d> points;
  std::vector<double> values;
  Eigen::VectorXd r;
  Eigen::MatrixXd dp, dv;
  for (const Constraint& c : constraints.constraints) {
    const ConstraintKind* kind = kinds ? kinds(c.kind) : nullptr;
    if (kind == nullptr)
      throw std::invalid_argument(label_of(c) + ": unknown constraint kind '" + c.kind + "'");
    kind->check(c);
    bool other_character = !c.channels.empty();
    for (const PointRef& p : c.points) other_character = other_character || p.character != 0;
    const int rows = kind->rows(c);
    if (other_character || c.points.empty()) {
      acc.ignored += rows * static_cast<int>(c.samples.size());
      continue;
    }
    for (const PointRef& p : c.points)
      if (p.joint < 0 || p.joint >= joints)
        throw std::invalid_argument(label_of(c) + ": joint index " + std::to_string(p.joint) +
                                    " outside the skeleton (" + std::to_string(joints) + " joints)");
    r.resize(rows);
    dp.resize(rows, 3 * static_cast<Eigen::Index>(c.points.size()));
    dv.resize(rows, 0);
    for (const Sample& sample : c.samples) {
      if (!one_instant(c, sample, frames)) {
        acc.ignored += rows;
        continue;
      }
      const int f = sample.frames.front();
      const std::vector<Eigen::Isometry3d>& w = pose(f);
      points.clear();
      for (std::size_t i = 0; i < c.points.size(); ++i) {
        const PointRef p = point_at(c, sample, i);
        points.push_back(w[static_cast<std::size_t>(p.joint)] * p.local);
      }
      const std::vector<double>& params = sample.params.empty() ? c.params : sample.params;
      r.setZero();
      dp.setZero();
      kind->evaluate(c, params, points, values, r, dp, dv);
      acc.add_rows(c, *kind, f, r, dp);
    }
  }
  if (rows_used != nullptr) *rows_used = acc.used;
  if (rows_ignored != nullptr) *rows_ignored = acc.ignored;
  return acc.resolve();
}

Eigen::MatrixXd fill_gaps(const Eigen::MatrixXd& raw) {
  Eigen::MatrixXd out = raw;
  const Eigen::Index n = raw.rows();
  for (Eigen::Index a = 0; a < raw.cols(); ++a) {
    Eigen::Index prev = -1;
    for (Eigen::Index f = 0; f < n; ++f) {
      if (std::isnan(raw(f, a))) continue;
      if (prev < 0) {
        for (Eigen::Index g = 0; g < f; ++g) out(g, a) = raw(f, a);  // held before the first
      } else {
        for (Eigen::Index g = prev + 1; g < f; ++g) {
          const double u = static_cast<double>(g - prev) / static_cast<double>(f - prev);
          out(g, a) = (1 - u) * raw(prev, a) + u * raw(f, a);
        }
      }
      prev = f;
    }
    if (prev < 0) {
      out.col(a).setZero();
    } else {
      for (Eigen::Index g = prev + 1; g < n; ++g) out(g, a) = raw(prev, a);  // held after the last
    }
  }
  return out;
}

Eigen::MatrixXd smooth_zero_phase(const Eigen::MatrixXd& x, double sigma) {
  if (!(sigma > 0) || x.rows() < 2) return x;
  const Eigen::Index n = x.rows();
  const int half = static_cast<int>(std::ceil(4 * sigma));
  std::vector<double> w(static_cast<std::size_t>(2 * half + 1));
  double total = 0;
  for (int i = -half; i <= half; ++i)
    total += w[static_cast<std::size_t>(i + half)] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& v : w) v /= total;
  auto at = [&](Eigen::Index col, Eigen::Index i) {
    if (i < 0) return 2 * x(0, col) - x(std::min<Eigen::Index>(-i, n - 1), col);
    if (i >= n) return 2 * x(n - 1, col) - x(std::max<Eigen::Index>(2 * (n - 1) - i, 0), col);
    return x(i, col);
  };
  Eigen::MatrixXd out(n, x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    for (Eigen::Index f = 0; f < n; ++f) {
      double sum = 0;
      for (int i = -half; i <= half; ++i) sum += w[static_cast<std::size_t>(i + half)] * at(c, f + i);
      out(f, c) = sum;
    }
  return out;
}

void InitialEstimateOptions::validate() const {
  options::require(options::non_negative(smooth_seconds), "InitialEstimateOptions", "smooth_seconds",
                   smooth_seconds, ">= 0 and finite (seconds; 0: no smoothing)");
}

InitialEstimate initial_estimate(const motion::Motion& source, const Target& target,
                                 const ConstraintSet* constraints, const KindFinder& kinds,
                                 const InitialEstimateOptions& options) {
  source.check();
  if (!target.source || !target.skeleton)
    throw std::invalid_argument("initial_estimate: the target has no skeleton");
  check_same_structure(*target.skeleton, *source.skeleton, "initial_estimate: the target");
  options.validate();

  InitialEstimate out;
  motion::Motion scaled = scale_translation(source, target, &out.scale);
  const int frames = source.frame_count();
  out.raw_shift = Eigen::MatrixXd::Constant(frames, 3, kNaN);
  if (constraints != nullptr && !constraints->constraints.empty())
    out.raw_shift =
        constraint_displacements(scaled, target, *constraints, kinds, &out.rows_used, &out.rows_ignored);
  for (int f = 0; f < frames; ++f) {
    bool any = false;
    for (int a = 0; a < 3; ++a)
      if (!std::isnan(out.raw_shift(f, a))) any = out.axes_fixed[static_cast<std::size_t>(a)] = true;
    out.constrained_frames += any;
  }
  out.shift = smooth_zero_phase(fill_gaps(out.raw_shift), options.smooth_seconds * source.fps);

  // Add the shift to every root's position channels, in file coordinates.
  const motion::Skeleton& s = *source.skeleton;
  const Eigen::Matrix3d world_to_file = s.file_to_world.transpose();
  for (int j = 0; j < s.joint_count(); ++j) {
    const motion::Joint& jt = s.joint(j);
    if (jt.parent >= 0) continue;
    std::array<int, 3> col{-1, -1, -1};
    for (std::size_t c = 0; c < jt.channels.size(); ++c)
      if (!motion::is_rotation(jt.channels[c].kind))
        col[static_cast<std::size_t>(motion::axis_index(jt.channels[c].kind))] =
            jt.first_channel + static_cast<int>(c);
    double lost = 0;
    for (int f = 0; f < frames; ++f) {
      const Eigen::Vector3d d = world_to_file * out.shift.row(f).transpose();
      for (int a = 0; a < 3; ++a) {
        if (col[static_cast<std::size_t>(a)] >= 0)
          scaled.values(f, col[static_cast<std::size_t>(a)]) += d[a];
        else
          lost = std::max(lost, std::abs(d[a]));
      }
    }
    if (lost > 1e-9) {
      std::ostringstream note;
      note << "root '" << jt.name << "' lacks a position channel for part of the shift (up to " << lost
           << " m not applied)";
      out.notes.push_back(note.str());
    }
  }
  scaled.skeleton = target.skeleton;
  out.motion = std::move(scaled);
  return out;
}

}  // namespace kg::retarget
