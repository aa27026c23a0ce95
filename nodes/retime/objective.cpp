#include "kg/retime/objective.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "kg/retime/force_model.hpp"

#include "kg/numerics/convex_nearest.hpp"

namespace kg::retime {

namespace {

// The hull's point nearest to x, walking from `edge` (out of line: evaluate's path for points
// inside their fan triangle stays short).
[[gnu::noinline]] HullPoint nearest(const Eigen::Vector2d* v, int n, const Eigen::Vector2d& x, int edge) {
  return n >= 3 ? numerics::nearest_from_edge(v, n, x, edge)
                : numerics::nearest_on_polygon(v, static_cast<std::size_t>(n), x);
}

}  // namespace

Quadratic bake_quadratic(const Eigen::VectorXd& t0, const Eigen::VectorXd& ta, const Eigen::VectorXd& tb,
                         const Eigen::VectorXd& target, double weight) {
  const Eigen::VectorXd r = t0 - target;
  return {weight * tb.squaredNorm(), weight * ta.squaredNorm(), 2 * weight * ta.dot(tb),
          2 * weight * tb.dot(r),    2 * weight * ta.dot(r),    weight * r.squaredNorm()};
}

std::vector<Eigen::VectorXd> original_torques(const Hulls& hulls, std::span<const FrameTorques> torques) {
  if (torques.size() != hulls.frames.size())
    throw std::invalid_argument("original torques: " + std::to_string(torques.size()) +
                                " frames of torques for " + std::to_string(hulls.frames.size()) + " hulls");
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
      for (std::size_t c = 0; c < joint.channels.size(); ++c)
        actuated[static_cast<std::size_t>(joint.first_channel) + c] = false;
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
    : hulls_(hulls), fps_(source_fps), weights_(weights), flight_alpha_(weights.alpha * weights.flight) {
  const std::size_t frames = hulls.frames.size();
  if (frames < 2) throw std::invalid_argument("retiming objective: fewer than 2 frames");
  if (torques.size() != frames || targets.size() != frames)
    throw std::invalid_argument("retiming objective: " + std::to_string(frames) + " hulls, " +
                                std::to_string(torques.size()) + " frames of torques and " +
                                std::to_string(targets.size()) + " target torques (expected equal)");
  if (!(source_fps > 0)) throw std::invalid_argument("retiming objective: fps must be > 0");
  if (!(weights.alpha >= 0) || !(weights.beta >= 0) || !(weights.flight >= 0) ||
      !(weights.torque_scale > 0) || !std::isfinite(flight_alpha_))
    throw std::invalid_argument(
        "retiming objective: alpha, beta and the flight weight must be finite and >= 0 and the torque scale "
        "> 0");
  const double w = weights.beta / (weights.torque_scale * weights.torque_scale);
  frames_.resize(frames);
  last_frame_ = static_cast<int>(frames) - 1;
  flight_.assign(frames, Quadratic{});
  flight_least_.assign(frames, 0.0);
  std::vector<int> root_rows;
  for (const motion::Joint& joint : skeleton.joints())
    if (joint.parent < 0)
      for (std::size_t c = 0; c < joint.channels.size(); ++c)
        root_rows.push_back(joint.first_channel + static_cast<int>(c));
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
    if (hull.sectors.empty())
      throw std::invalid_argument("retiming objective: frame " + std::to_string(f) + " has no fan");
    const int n = static_cast<int>(hull.vertices.size());
    FrameData& frame = frames_[f];
    frame.centre_x = hull.centre.x();
    frame.centre_y = hull.centre.y();
    frame.first_sector = static_cast<int>(sectors_.size());
    frame.sector_count = static_cast<int>(hull.sectors.size());
    frame.first_vertex = static_cast<int>(vertices_.size());
    frame.vertex_count = n;
    frame.flight = hull.status == HullStatus::Flight;
    vertices_.insert(vertices_.end(), hull.vertices.begin(), hull.vertices.end());
    for (std::size_t s = 0; s < hull.sectors.size(); ++s) {
      const FanSector& fan = hull.sectors[s];
      SectorData d{};
      d.from_x = fan.from.x();
      d.from_y = fan.from.y();
      d.to_x = fan.to.x();
      d.to_y = fan.to.y();
      // Without contact forces every sector has the same τ: bake it once.
      if (s > 0 && hull.N.cols() == 0) {
        d.q = sectors_[static_cast<std::size_t>(frame.first_sector)].q;
      } else {
        sector_torques(hull, static_cast<int>(s), torques[f], hulls.gravity, t);
        d.q = bake_quadratic(t.t0, t.pddot, t.pdot2, targets[f], w);
      }
      d.edge = std::clamp(fan.edge, 0, n - 1);
      d.triangle = fan.in_hull && n >= 3;
      d.length_squared = -1;
      if (n >= 3) {
        const auto at = [&](int i) -> const Eigen::Vector2d& {
          return hull.vertices[static_cast<std::size_t>((i + n) % n)];
        };
        const Eigen::Vector2d e = at(d.edge + 1) - at(d.edge), before = at(d.edge) - at(d.edge - 1),
                              after = at(d.edge + 2) - at(d.edge + 1);
        d.edge_x = at(d.edge).x();
        d.edge_y = at(d.edge).y();
        d.along_x = e.x();
        d.along_y = e.y();
        if (e.squaredNorm() > 0) d.length_squared = e.squaredNorm();
        d.before_x = before.x();
        d.before_y = before.y();
        d.end_x = at(d.edge + 1).x();
        d.end_y = at(d.edge + 1).y();
        d.after_x = after.x();
        d.after_y = after.y();
      }
      sectors_.push_back(d);
    }
  }
}

SampleCost BakedObjective::evaluate(double p, double pddot, double pdot_squared, int& hint) const {
  // One frame's integrand at (a, b) = (p̈, ṗ²); `sector`: the search's start, set to a's sector.
  // A lambda forced inline, not a member (a member of a shared library is called through its
  // PLT): both frames' work then interleaves, each with its own branch sites.
  struct FrameCost {
    double value, d_a, d_b;
  };
  auto frame_cost = [this](int frame, double a, double b, int& sector) __attribute__((always_inline)) {
    const FrameData& fr = frames_[static_cast<std::size_t>(frame)];
    const SectorData* sectors = sectors_.data() + fr.first_sector;
    const int n = fr.sector_count;
    int k = sector >= 0 && sector < n ? sector : 0;
    // find_sector's search on the baked copy (the same tests in the same order, so the same sector;
    // the hint's sector first, as it nearly always holds the sample; at the centre every sector
    // holds it, and find_sector returns the hint's).
    const double dx = a - fr.centre_x, dy = b - fr.centre_y;
    auto holds = [&](const SectorData& s) {
      return s.from_x * dy - s.from_y * dx >= 0 && dx * s.to_y - dy * s.to_x >= 0;
    };
    if (!holds(sectors[k])) [[unlikely]] {
      const bool back = sectors[k].from_x * dy - sectors[k].from_y * dx < 0;
      int i = 1;
      for (; i < n; ++i) {
        k = back ? (k == 0 ? n - 1 : k - 1) : (k + 1 == n ? 0 : k + 1);
        if (holds(sectors[k])) break;
      }
      // Rounding on a ray: find_sector's choice of the sector the point is nearest to being inside.
      if (i == n) k = find_sector(hulls_.frames[static_cast<std::size_t>(frame)], Eigen::Vector2d(a, b), k);
    }
    sector = k;
    const SectorData& s = sectors[k];
    // kg::retime::evaluate and its partial derivatives, sharing products ((2 q1) a = 2 (q1 a)
    // exactly, so the results are the same).
    const Quadratic& q = s.q;
    const double qb = q[0] * b, qa = q[1] * a, qab = q[2] * a;
    FrameCost cost{qb * b + qa * a + qab * b + q[3] * b + q[4] * a + q[5], qa + qa + q[2] * b + q[4],
                   qb + qb + qab + q[3]};
    // Inside the sector's fan triangle is inside the hull: no nearest point to find.
    const double rx = a - s.edge_x, ry = b - s.edge_y;
    const double side = s.along_x * ry - s.along_y * rx;
    if (s.triangle && side >= 0) return cost;
    if (fr.flight) [[unlikely]] {
      const Quadratic& r = flight_[static_cast<std::size_t>(frame)];
      const double alpha = flight_alpha_;
      cost.value += alpha * kg::retime::evaluate(r, a, b);
      cost.d_a += alpha * (2 * r[1] * a + r[2] * b + r[4]);
      cost.d_b += alpha * (2 * r[0] * b + r[2] * a + r[3]);
      return cost;
    }
    const double alpha = weights_.alpha;
    // The nearest point: nearest_from_edge's first step on the facing edge (the same arithmetic),
    // which nearly always concludes (the foot on the edge, or one of its ends), else the walk.
    double gap_x = 0, gap_y = 0;
    bool found = false;
    if (s.length_squared > 0) {
      const double along = rx * s.along_x + ry * s.along_y;
      if (along < 0) {
        found = rx * s.before_x + ry * s.before_y >= 0;
        gap_x = rx, gap_y = ry;
      } else if (along > s.length_squared) {
        gap_x = a - s.end_x, gap_y = b - s.end_y;
        found = gap_x * s.after_x + gap_y * s.after_y <= 0;
      } else if (side <= 0) {
        found = true;
        const double t = along / s.length_squared;
        gap_x = a - (s.edge_x + t * s.along_x), gap_y = b - (s.edge_y + t * s.along_y);
      }
    }
    if (!found) {
      const Eigen::Vector2d x(a, b);
      const HullPoint c = nearest(vertices_.data() + fr.first_vertex, fr.vertex_count, x, s.edge);
      if (c.inside) return cost;
      gap_x = a - c.point.x(), gap_y = b - c.point.y();
    }
    cost.value += alpha * (gap_x * gap_x + gap_y * gap_y);
    cost.d_a += 2 * alpha * gap_x;
    cost.d_b += 2 * alpha * gap_y;
    return cost;
  };
  const int last = last_frame_;
  const double x = std::clamp(p * fps_, 0.0, static_cast<double>(last));
  const int f = std::min(static_cast<int>(x), last - 1);
  const double u = x - f;
  // The hint packs the sectors of frames `tag` and `tag` + 1 (10 bits each; the tag is the frame
  // index's low 11 bits): the same pair starts both searches where they ended, the next pair
  // starts frame f from what was frame f + 1.
  const auto h = static_cast<unsigned>(hint);
  const unsigned tag = (h >> 20) & 0x7ffu, mine = static_cast<unsigned>(f) & 0x7ffu;
  int s0 = static_cast<int>(h & 0x3ffu), s1 = static_cast<int>((h >> 10) & 0x3ffu);
  if (tag != mine) {
    s0 = tag == ((mine - 1) & 0x7ffu) ? s1 : s0;
    s1 = s0;
  }
  const FrameCost c0 = frame_cost(f, pddot, pdot_squared, s0);
  const FrameCost c1 = frame_cost(f + 1, pddot, pdot_squared, s1);
  hint = static_cast<int>((static_cast<unsigned>(s0) & 0x3ffu) | (static_cast<unsigned>(s1) & 0x3ffu) << 10 |
                          mine << 20);
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
  const Eigen::Vector2d lambda =
      eig.eigenvalues().cwiseMax(1e-12 * std::max(1.0, eig.eigenvalues().maxCoeff()));
  const Eigen::Matrix2d V = eig.eigenvectors();
  const Eigen::Vector2d m = -0.5 * (V * (V.transpose() * g).cwiseQuotient(lambda));
  const double level = tolerance * tolerance - (kg::retime::evaluate(q, m.x(), m.y()) +
                                                flight_least_[static_cast<std::size_t>(frame)]);
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

BakedObjective::Parts BakedObjective::parts(int frame, double pddot, double pdot_squared,
                                            double tolerance) const {
  const FrameHull& hull = hulls_.frames.at(static_cast<std::size_t>(frame));
  const Eigen::Vector2d x(pddot, pdot_squared);
  int hint = 0;
  const int sector = find_sector(hull, x, hint);
  Parts out;
  out.torque = kg::retime::evaluate(quadratic(frame, sector), pddot, pdot_squared);
  hint = sector;
  const HullPoint c = closest_point(hull, x, hint);
  out.feasibility = hull.status == HullStatus::Flight
                        ? flight_alpha_ * kg::retime::evaluate(flight_[static_cast<std::size_t>(frame)],
                                                               pddot, pdot_squared)
                        : weights_.alpha * c.distance_squared;
  out.inside = c.distance_squared <= tolerance * tolerance;
  return out;
}

}  // namespace kg::retime
