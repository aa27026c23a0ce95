#include "kg/retime/objective.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace kg::retime {

namespace {

double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

Eigen::Vector2d closest_on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& q) {
  const Eigen::Vector2d d = b - a;
  const double length2 = d.squaredNorm();
  if (length2 == 0) return a;
  return a + d * std::clamp((q - a).dot(d) / length2, 0.0, 1.0);
}

}  // namespace

Quadratic bake_quadratic(const Eigen::VectorXd& t0, const Eigen::VectorXd& ta, const Eigen::VectorXd& tb,
                         const Eigen::VectorXd& target, double weight) {
  const Eigen::VectorXd r = t0 - target;
  return {weight * tb.squaredNorm(), weight * ta.squaredNorm(), 2 * weight * ta.dot(tb),
          2 * weight * tb.dot(r),    2 * weight * ta.dot(r),    weight * r.squaredNorm()};
}

Eigen::Vector2d closest_point(const std::vector<Eigen::Vector2d>& vertices, const Eigen::Vector2d& q) {
  const std::size_t n = vertices.size();
  if (n == 0) throw std::invalid_argument("closest point: empty polygon");
  if (n == 1) return vertices[0];
  if (n == 2) return closest_on_segment(vertices[0], vertices[1], q);
  bool inside = true;
  for (std::size_t i = 0; i < n && inside; ++i)
    inside = cross(vertices[(i + 1) % n] - vertices[i], q - vertices[i]) >= 0;
  if (inside) return q;
  Eigen::Vector2d best = vertices[0];
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d c = closest_on_segment(vertices[i], vertices[(i + 1) % n], q);
    const double d = (c - q).squaredNorm();
    if (d < best_distance) best_distance = d, best = c;
  }
  return best;
}

void BakedObjective::add_frame(BakedFrame frame) {
  if (frame.vertices.empty()) throw std::invalid_argument("baked objective: a frame without a hull");
  const std::size_t sectors = frame.vertices.size() >= 3 ? frame.vertices.size() : 1;
  if (frame.sectors.size() != sectors)
    throw std::invalid_argument("baked objective: frame " + std::to_string(frames_.size()) + " has " +
                                std::to_string(frame.sectors.size()) + " sectors for " +
                                std::to_string(frame.vertices.size()) + " hull vertices");
  frames_.push_back(std::move(frame));
}

void BakedObjective::finish() {
  if (frames_.size() < 2) throw std::invalid_argument("baked objective: fewer than 2 frames");
  for (BakedFrame& f : frames_) {
    f.angles.clear();
    if (f.vertices.size() < 3) continue;
    double previous = -std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& v : f.vertices) {
      double angle = std::atan2(v.y() - f.centre.y(), v.x() - f.centre.x());
      while (angle < previous) angle += 2 * std::numbers::pi;
      f.angles.push_back(angle);
      previous = angle;
    }
  }
}

int BakedObjective::sector_of(const BakedFrame& f, const Eigen::Vector2d& q, int hint) const {
  const int n = static_cast<int>(f.vertices.size());
  if (n < 3) return 0;
  const Eigen::Vector2d d = q - f.centre;
  // Walk from the hint: sector k holds the directions from ray k (inclusive) to ray k + 1.
  int k = ((hint % n) + n) % n;
  for (int step = 0; step < 3; ++step) {
    const bool after_k = cross(f.vertices[static_cast<std::size_t>(k)] - f.centre, d) >= 0;
    const bool before_next = cross(f.vertices[static_cast<std::size_t>((k + 1) % n)] - f.centre, d) < 0;
    if (after_k && before_next) return k;
    k = after_k ? (k + 1) % n : (k + n - 1) % n;
  }
  // Far from the hint: by angle.
  double angle = std::atan2(d.y(), d.x());
  while (angle < f.angles.front()) angle += 2 * std::numbers::pi;
  while (angle >= f.angles.front() + 2 * std::numbers::pi) angle -= 2 * std::numbers::pi;
  const auto it = std::upper_bound(f.angles.begin(), f.angles.end(), angle);
  return static_cast<int>(it - f.angles.begin()) - 1;
}

BakedObjective::FrameCost BakedObjective::frame_cost(int frame, double a, double b, int& sector_hint) const {
  const BakedFrame& f = frames_[static_cast<std::size_t>(frame)];
  const Eigen::Vector2d q(a, b);
  const int sector = sector_of(f, q, sector_hint);
  sector_hint = sector;
  const Quadratic& s = f.sectors[static_cast<std::size_t>(sector)];
  FrameCost cost{s[0] * b * b + s[1] * a * a + s[2] * a * b + s[3] * b + s[4] * a + s[5],
                 2 * s[1] * a + s[2] * b + s[4], 2 * s[0] * b + s[2] * a + s[3]};
  // Inside the sector's triangle is inside the hull: no feasibility term to find.
  const int n = static_cast<int>(f.vertices.size());
  if (n >= 3) {
    const Eigen::Vector2d& u = f.vertices[static_cast<std::size_t>(sector)];
    const Eigen::Vector2d& v = f.vertices[static_cast<std::size_t>((sector + 1) % n)];
    if (cross(v - u, q - u) >= 0) return cost;
  }
  const Eigen::Vector2d gap = q - closest_point(f.vertices, q);
  cost.value += alpha_ * gap.squaredNorm();
  cost.d_a += 2 * alpha_ * gap.x();
  cost.d_b += 2 * alpha_ * gap.y();
  return cost;
}

SampleCost BakedObjective::evaluate(double p, double pddot, double pdot_squared, int& hint) const {
  const int last = static_cast<int>(frames_.size()) - 1;
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

BakedObjective::Parts BakedObjective::parts(int frame, double pddot, double pdot_squared, double tolerance) const {
  const BakedFrame& f = frames_.at(static_cast<std::size_t>(frame));
  const Eigen::Vector2d q(pddot, pdot_squared);
  Parts out;
  out.sector = sector_of(f, q, 0);
  const Quadratic& s = f.sectors[static_cast<std::size_t>(out.sector)];
  out.torque = s[0] * pdot_squared * pdot_squared + s[1] * pddot * pddot + s[2] * pddot * pdot_squared +
               s[3] * pdot_squared + s[4] * pddot + s[5];
  const double gap = (q - closest_point(f.vertices, q)).norm();
  out.feasibility = alpha_ * gap * gap;
  out.inside = gap <= tolerance;
  return out;
}

}  // namespace kg::retime
