#include "kg/retime/objective.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "kg/retime/force_model.hpp"

namespace kg::retime {

namespace {

double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

}  // namespace

Quadratic bake_quadratic(const Eigen::VectorXd& t0, const Eigen::VectorXd& ta, const Eigen::VectorXd& tb,
                         const Eigen::VectorXd& target, double weight) {
  const Eigen::VectorXd r = t0 - target;
  return {weight * tb.squaredNorm(), weight * ta.squaredNorm(), 2 * weight * ta.dot(tb),
          2 * weight * tb.dot(r),    2 * weight * ta.dot(r),    weight * r.squaredNorm()};
}

std::vector<Eigen::VectorXd> original_torques(const Hulls& hulls, std::span<const FrameTorques> torques) {
  if (torques.size() != hulls.frames.size())
    throw std::invalid_argument("original torques: " + std::to_string(torques.size()) + " frames of torques for " +
                                std::to_string(hulls.frames.size()) + " hulls");
  std::vector<Eigen::VectorXd> out;
  out.reserve(torques.size());
  SectorTorques t;
  for (std::size_t f = 0; f < torques.size(); ++f) {
    const FrameHull& hull = hulls.frames[f];
    const Eigen::Vector2d original(0, 1);
    const int sector = find_sector(hull, original, 0);
    sector_torques(hull, sector, torques[f], hulls.gravity, t);
    out.push_back(t.t0 + t.pdot2);
  }
  return out;
}

double torque_scale(const motion::Skeleton& skeleton, std::span<const Eigen::VectorXd> torques) {
  std::vector<bool> actuated(static_cast<std::size_t>(skeleton.channel_count()), true);
  for (const motion::Joint& joint : skeleton.joints())
    if (joint.parent < 0)
      for (std::size_t c = 0; c < joint.channels.size(); ++c) actuated[static_cast<std::size_t>(joint.first_channel) + c] = false;
  double sum = 0;
  long count = 0;
  for (const Eigen::VectorXd& tau : torques)
    for (Eigen::Index c = 0; c < tau.size() && c < static_cast<Eigen::Index>(actuated.size()); ++c)
      if (actuated[static_cast<std::size_t>(c)]) sum += tau[c] * tau[c], ++count;
  const double rms = count ? std::sqrt(sum / count) : 0.0;
  return rms > 0 && std::isfinite(rms) ? rms : 1.0;
}

BakedObjective::BakedObjective(const Hulls& hulls, std::span<const FrameTorques> torques,
                               std::span<const Eigen::VectorXd> targets, const motion::Skeleton& skeleton,
                               double source_fps, const ObjectiveWeights& weights)
    : hulls_(hulls), fps_(source_fps), weights_(weights) {
  const std::size_t frames = hulls.frames.size();
  if (frames < 2) throw std::invalid_argument("retiming objective: fewer than 2 frames");
  if (torques.size() != frames || targets.size() != frames)
    throw std::invalid_argument("retiming objective: " + std::to_string(frames) + " hulls, " +
                                std::to_string(torques.size()) + " frames of torques and " +
                                std::to_string(targets.size()) + " target torques (expected equal)");
  if (!(source_fps > 0)) throw std::invalid_argument("retiming objective: fps must be > 0");
  if (!(weights.alpha >= 0) || !(weights.beta >= 0) || !(weights.torque_scale > 0))
    throw std::invalid_argument("retiming objective: alpha and beta must be >= 0 and the torque scale > 0");
  const double w = weights.beta / (weights.torque_scale * weights.torque_scale);
  quadratics_.resize(frames);
  flight_.assign(frames, Quadratic{});
  flight_least_.assign(frames, 0.0);
  std::vector<int> root_rows;
  for (const motion::Joint& joint : skeleton.joints())
    if (joint.parent < 0)
      for (std::size_t c = 0; c < joint.channels.size(); ++c) root_rows.push_back(joint.first_channel + static_cast<int>(c));
  SectorTorques t;
  for (std::size_t f = 0; f < frames; ++f) {
    const FrameHull& hull = hulls.frames[f];
    if (hull.status == HullStatus::Flight && !root_rows.empty()) {
      const FrameTorques& ft = torques[f];
      const auto n = static_cast<Eigen::Index>(root_rows.size());
      Eigen::VectorXd r0(n), ra(n), rb(n);
      for (Eigen::Index i = 0; i < n; ++i) {
        const int c = root_rows[static_cast<std::size_t>(i)];
        r0[i] = ft.gravity.row(c).dot(hulls.gravity);
        ra[i] = ft.acceleration[c];
        rb[i] = ft.velocity[c];
      }
      // The weight: what the root's rows need to hold the body still.
      const double weight = std::max(r0.norm(), 1e-9);
      // Unweighted (|r|² / W²): α multiplies it where it is used, so α = 0 keeps the region.
      Quadratic q = bake_quadratic(r0, ra, rb, Eigen::VectorXd::Zero(n), 1 / (weight * weight));
      flight_least_[f] = kg::retime::evaluate(q, hull.vertices[0].x(), hull.vertices[0].y());
      q[5] -= flight_least_[f];  // 0 at the closest point
      flight_[f] = q;
    }
    quadratics_[f].reserve(hull.sectors.size());
    for (std::size_t s = 0; s < hull.sectors.size(); ++s) {
      // Without contact forces every sector has the same τ: bake it once.
      if (s > 0 && hull.N.cols() == 0) {
        quadratics_[f].push_back(quadratics_[f].front());
        continue;
      }
      sector_torques(hull, static_cast<int>(s), torques[f], hulls.gravity, t);
      quadratics_[f].push_back(bake_quadratic(t.t0, t.pddot, t.pdot2, targets[f], w));
    }
  }
}

BakedObjective::FrameCost BakedObjective::frame_cost(int frame, double a, double b, int& hint) const {
  const FrameHull& hull = hulls_.frames[static_cast<std::size_t>(frame)];
  const Eigen::Vector2d x(a, b);
  hint = find_sector(hull, x, hint);
  const Quadratic& q = quadratics_[static_cast<std::size_t>(frame)][static_cast<std::size_t>(hint)];
  FrameCost cost{kg::retime::evaluate(q, a, b), 2 * q[1] * a + q[2] * b + q[4], 2 * q[0] * b + q[2] * a + q[3]};
  if (hull.status == HullStatus::Flight) {
    const Quadratic& r = flight_[static_cast<std::size_t>(frame)];
    const double alpha = weights_.alpha;
    cost.value += alpha * kg::retime::evaluate(r, a, b);
    cost.d_a += alpha * (2 * r[1] * a + r[2] * b + r[4]);
    cost.d_b += alpha * (2 * r[0] * b + r[2] * a + r[3]);
    return cost;
  }
  // Inside the sector's fan triangle is inside the hull: no nearest point to find.
  const FanSector& s = hull.sectors[static_cast<std::size_t>(hint)];
  const int n = static_cast<int>(hull.vertices.size());
  if (s.in_hull && n >= 3) {
    const Eigen::Vector2d& u = hull.vertices[static_cast<std::size_t>(s.edge)];
    const Eigen::Vector2d& v = hull.vertices[static_cast<std::size_t>((s.edge + 1) % n)];
    if (cross(v - u, x - u) >= 0) return cost;
  }
  int probe = hint;
  const HullPoint c = closest_point(hull, x, probe);
  if (c.inside) return cost;
  const Eigen::Vector2d gap = x - c.point;
  cost.value += weights_.alpha * gap.squaredNorm();
  cost.d_a += 2 * weights_.alpha * gap.x();
  cost.d_b += 2 * weights_.alpha * gap.y();
  return cost;
}

SampleCost BakedObjective::evaluate(double p, double pddot, double pdot_squared, int& hint) const {
  const int last = static_cast<int>(quadratics_.size()) - 1;
  const double x = std::clamp(p * fps_, 0.0, static_cast<double>(last));
  const int f = std::min(static_cast<int>(x), last - 1);
  const double u = x - f;
  int sector = hint;
  const FrameCost c0 = frame_cost(f, pddot, pdot_squared, sector);
  hint = sector;
  const FrameCost c1 = frame_cost(f + 1, pddot, pdot_squared, sector);
  return {.value = (1 - u) * c0.value + u * c1.value,
          .d_p = (c1.value - c0.value) * fps_,
          .d_pddot = (1 - u) * c0.d_a + u * c1.d_a,
          .d_pdot2 = (1 - u) * c0.d_b + u * c1.d_b};
}

Polygon BakedObjective::admissible_region(int frame, double tolerance, int sides, double extent) const {
  const FrameHull& hull = hulls_.frames.at(static_cast<std::size_t>(frame));
  if (hull.status == HullStatus::Feasible) return hull.vertices;
  if (hull.status == HullStatus::Infeasible) return {};
  const Quadratic& q = flight_[static_cast<std::size_t>(frame)];
  // Q(x) = x^T A x + g^T x + q5 with x = (p̈, ṗ²); its minimum m and the ellipse Q <= α tol².
  Eigen::Matrix2d A;
  A << q[1], q[2] / 2, q[2] / 2, q[0];
  const Eigen::Vector2d g(q[4], q[3]);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(A);
  const Eigen::Vector2d lambda = eig.eigenvalues().cwiseMax(1e-12 * std::max(1.0, eig.eigenvalues().maxCoeff()));
  const Eigen::Matrix2d V = eig.eigenvectors();
  const Eigen::Vector2d m = -0.5 * (V * (V.transpose() * g).cwiseQuotient(lambda));
  const double level = tolerance * tolerance -
                       (kg::retime::evaluate(q, m.x(), m.y()) + flight_least_[static_cast<std::size_t>(frame)]);
  Polygon out;
  if (!(level > 0)) return out;
  for (int k = 0; k < sides; ++k) {
    const double angle = 2 * std::numbers::pi * k / sides;
    Eigen::Vector2d u(std::cos(angle), std::sin(angle));
    for (int i = 0; i < 2; ++i) u[i] *= std::min(std::sqrt(level / lambda[i]), extent);
    out.push_back(m + V * u);
  }
  if (V.determinant() < 0) std::reverse(out.begin(), out.end());  // keep counter-clockwise
  return out;
}

BakedObjective::Parts BakedObjective::parts(int frame, double pddot, double pdot_squared, double tolerance) const {
  const FrameHull& hull = hulls_.frames.at(static_cast<std::size_t>(frame));
  const Eigen::Vector2d x(pddot, pdot_squared);
  int hint = 0;
  const int sector = find_sector(hull, x, hint);
  Parts out;
  out.torque = kg::retime::evaluate(quadratic(frame, sector), pddot, pdot_squared);
  hint = sector;
  const HullPoint c = closest_point(hull, x, hint);
  out.feasibility = hull.status == HullStatus::Flight
                        ? weights_.alpha * kg::retime::evaluate(flight_[static_cast<std::size_t>(frame)], pddot, pdot_squared)
                        : weights_.alpha * c.distance_squared;
  out.inside = c.distance_squared <= tolerance * tolerance;
  return out;
}

}  // namespace kg::retime
