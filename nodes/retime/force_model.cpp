// The fan force model (force_model.hpp): sectors about each hull's centre, λ and τ affine in each.
#include "kg/retime/force_model.hpp"

#include "kg/numerics/convex_nearest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace kg::retime {

namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}
Eigen::Vector2d rotate_ccw(const Eigen::Vector2d& v) {
  return {-v.y(), v.x()};
}
Eigen::Vector2d rotate_cw(const Eigen::Vector2d& v) {
  return {v.y(), -v.x()};
}

// A ray of the fan: direction from the centre and λ at centre + direction.
struct Node {
  Eigen::Vector2d dir;
  const Eigen::VectorXd* lambda;  // not owned
  int vertex;                     // hull vertex, -1 for a normal (λ = the centre's)
};

}  // namespace

void build_fan(FrameHull& h) {
  const int n = static_cast<int>(h.vertices.size());
  if (n == 0) throw std::invalid_argument("force model: the hull has no vertex");
  if (static_cast<int>(h.lambda.size()) != n)
    throw std::invalid_argument("force model: " + std::to_string(h.lambda.size()) + " λ vectors for " +
                                std::to_string(n) + " vertices");
  const Eigen::Index k = h.centre_lambda.size();
  for (const Eigen::VectorXd& l : h.lambda)
    if (l.size() != k)
      throw std::invalid_argument("force model: λ sizes of the vertices and the centre differ");
  double extent = 1;
  for (const Eigen::Vector2d& v : h.vertices) extent = std::max(extent, v.cwiseAbs().maxCoeff());
  const double eps = 1e-9 * extent;
  const Eigen::Vector2d c = h.centre;
  if (n >= 3)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d e =
          h.vertices[static_cast<std::size_t>((i + 1) % n)] - h.vertices[static_cast<std::size_t>(i)];
      if (cross(e, c - h.vertices[static_cast<std::size_t>(i)]) < -eps * e.norm())
        throw std::invalid_argument("force model: the centre lies outside the hull");
    }

  // Rays through the hull's vertices, in their (counter-clockwise) order; a vertex at the centre
  // is the centre.
  std::vector<Node> rays;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d d = h.vertices[static_cast<std::size_t>(i)] - c;
    if (d.norm() > eps) rays.push_back({d, &h.lambda[static_cast<std::size_t>(i)], i});
  }
  h.sectors.clear();
  auto add = [&](const Node& a, const Node& b, int edge, bool in_hull) {
    FanSector s;
    s.from = a.dir;
    s.to = b.dir;
    s.edge = edge;
    s.in_hull = in_hull;
    Eigen::MatrixXd slope = Eigen::MatrixXd::Zero(k, 2);  // k x 2: dλ/dp̈, dλ/dṗ²
    // Between two normals λ is the centre's: no slope (and the half-turn wedge of a one-ray fan
    // has no basis to invert).
    if (a.lambda || b.lambda) {
      Eigen::Matrix2d basis;
      basis << a.dir, b.dir;
      const Eigen::Matrix2d inverse = basis.inverse();  // (α, β) = inverse * (x − c)
      Eigen::MatrixXd delta(k, 2);
      delta.col(0) = (a.lambda ? *a.lambda : h.centre_lambda) - h.centre_lambda;
      delta.col(1) = (b.lambda ? *b.lambda : h.centre_lambda) - h.centre_lambda;
      slope = delta * inverse;
    }
    s.lambda_pddot = slope.col(0);
    s.lambda_pdot2 = slope.col(1);
    s.lambda0 = h.centre_lambda - slope * c;
    h.sectors.push_back(std::move(s));
  };
  if (rays.empty()) {
    // A one-point hull: λ is the centre's everywhere.
    const Eigen::Vector2d axes[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    for (int i = 0; i < 4; ++i) add({axes[i], nullptr, -1}, {axes[(i + 1) % 4], nullptr, -1}, 0, false);
    return;
  }
  const int r = static_cast<int>(rays.size());
  for (int i = 0; i < r; ++i) {
    const Node& a = rays[static_cast<std::size_t>(i)];
    const Node& b = rays[static_cast<std::size_t>((i + 1) % r)];
    double angle = std::atan2(cross(a.dir, b.dir), a.dir.dot(b.dir));
    if (r == 1 || angle <= 0) angle += 2 * std::numbers::pi;
    const bool gap = angle >= std::numbers::pi - 1e-9;
    if (!gap) {
      add(a, b, a.vertex, true);
      continue;
    }
    // The centre is on the boundary between a and b: fill the wedge outside with the edges'
    // outward normals (one when the wedge is a half-plane).
    const int last_edge = (b.vertex - 1 + n) % n;
    const Node na{rotate_ccw(a.dir).normalized() * a.dir.norm(), nullptr, -1};
    const Node nb{rotate_cw(b.dir).normalized() * b.dir.norm(), nullptr, -1};
    if (angle <= std::numbers::pi + 1e-9) {
      add(a, na, a.vertex, false);
      add(na, b, last_edge, false);
    } else {
      add(a, na, a.vertex, false);
      add(na, nb, a.vertex, false);
      add(nb, b, last_edge, false);
    }
  }
}

int find_sector(const FrameHull& h, const Eigen::Vector2d& x, int hint) {
  const int n = static_cast<int>(h.sectors.size());
  if (n == 0) throw std::invalid_argument("force model: the hull has no fan (build_fan)");
  int k = hint >= 0 && hint < n ? hint : 0;
  const Eigen::Vector2d d = x - h.centre;
  if (d.x() == 0 && d.y() == 0) return k;
  // Walk one way round from the hint (a fixed direction always ends within n steps; the first
  // test picks the nearer way for a nearby query). Exact tests first: no norms on the hot path.
  const bool back = cross(h.sectors[static_cast<std::size_t>(k)].from, d) < 0;
  for (int i = 0; i < n; ++i, k = back ? (k == 0 ? n - 1 : k - 1) : (k + 1 == n ? 0 : k + 1)) {
    const FanSector& s = h.sectors[static_cast<std::size_t>(k)];
    if (cross(s.from, d) >= 0 && cross(d, s.to) >= 0) return k;
  }
  // Rounding on a ray: accept the sector the point is nearest to being inside.
  const double dn = d.norm();
  int best = 0;
  double best_slack = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const FanSector& s = h.sectors[static_cast<std::size_t>(i)];
    const double slack =
        std::max({0.0, -cross(s.from, d) / (s.from.norm() * dn), -cross(d, s.to) / (s.to.norm() * dn)});
    if (slack < best_slack) {
      best_slack = slack;
      best = i;
    }
  }
  return best;
}

void lambda_at(const FrameHull& h, const Eigen::Vector2d& x, int& hint, Eigen::VectorXd& lambda) {
  hint = find_sector(h, x, hint);
  const FanSector& s = h.sectors[static_cast<std::size_t>(hint)];
  lambda.resize(s.lambda0.size());
  lambda.noalias() = s.lambda0 + s.lambda_pddot * x.x() + s.lambda_pdot2 * x.y();
}

void sector_torques(const FrameHull& h, int sector, const FrameTorques& t, const Eigen::Vector3d& gravity,
                    SectorTorques& out) {
  if (sector < 0 || sector >= static_cast<int>(h.sectors.size()))
    throw std::invalid_argument("force model: sector " + std::to_string(sector) + " out of range");
  const FanSector& s = h.sectors[static_cast<std::size_t>(sector)];
  const Eigen::Index channels = t.velocity.size();
  if (t.acceleration.size() != channels || t.gravity.rows() != channels || h.N.rows() != channels)
    throw std::invalid_argument("force model: the torque coefficients and N have different channel counts");
  out.t0.resize(channels);
  out.pddot.resize(channels);
  out.pdot2.resize(channels);
  out.t0.noalias() = t.gravity * gravity;
  out.pddot = t.acceleration;
  out.pdot2 = t.velocity;
  if (h.N.cols() > 0) {
    out.t0.noalias() -= h.N * s.lambda0;
    out.pddot.noalias() -= h.N * s.lambda_pddot;
    out.pdot2.noalias() -= h.N * s.lambda_pdot2;
  }
}

std::vector<PatchForce> patch_forces(const FrameHull& h, const Eigen::VectorXd& lambda) {
  if (lambda.size() != h.N.cols())
    throw std::invalid_argument("force model: " + std::to_string(lambda.size()) + " λ for " +
                                std::to_string(h.N.cols()) + " columns");
  std::vector<PatchForce> out;
  std::vector<double> vertical;
  std::vector<int> count;
  std::vector<Eigen::Vector3d> mean;
  for (Eigen::Index j = 0; j < lambda.size(); ++j) {
    const int patch = h.column_patch[static_cast<std::size_t>(j)];
    if (out.empty() || out.back().patch != patch) {
      out.push_back({patch, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
      vertical.push_back(0);
      count.push_back(0);
      mean.push_back(Eigen::Vector3d::Zero());
    }
    const Eigen::Vector3d f = h.force_directions.col(j) * lambda[j];
    out.back().force += f;
    out.back().centre_of_pressure += h.points.col(j) * f.y();
    vertical.back() += f.y();
    mean.back() += h.points.col(j);
    ++count.back();
  }
  for (std::size_t p = 0; p < out.size(); ++p) {
    if (std::abs(vertical[p]) > 1e-12)
      out[p].centre_of_pressure /= vertical[p];
    else
      out[p].centre_of_pressure = mean[p] / count[p];
  }
  return out;
}

HullPoint closest_point_on_polygon(std::span<const Eigen::Vector2d> v, const Eigen::Vector2d& x) {
  if (v.empty()) throw std::invalid_argument("closest point: the polygon has no vertex");
  return numerics::nearest_on_polygon(v.data(), v.size(), x);
}

HullPoint closest_point(const FrameHull& h, const Eigen::Vector2d& x, int& hint) {
  const int n = static_cast<int>(h.vertices.size());
  if (n < 3) return closest_point_on_polygon(h.vertices, x);
  hint = find_sector(h, x, hint);
  const FanSector& s = h.sectors[static_cast<std::size_t>(hint)];
  const Eigen::Vector2d& u = h.vertices[static_cast<std::size_t>(s.edge)];
  if (s.in_hull && cross(h.vertices[static_cast<std::size_t>((s.edge + 1) % n)] - u, x - u) >= 0)
    return {x, 0.0, true};
  // x is beyond edge s.edge, or in a wedge outside at the centre (which touches that edge): the
  // walk from there is short.
  return numerics::nearest_from_edge(h.vertices.data(), n, x, s.edge);
}

}  // namespace kg::retime
