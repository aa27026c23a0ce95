// The point of a convex polygon nearest to a query, inline so that a caller's per-sample path
// (the retiming's objective) inlines it. Any consistent plane units; `v` points to `n` vertices
// counter-clockwise (not owned).
//
//   NearestPoint c = nearest_from_edge(h.vertices.data(), n, x, sector.edge);
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include <Eigen/Core>

namespace kg::numerics {

// The nearest point, its squared distance to the query, and whether the query lies inside
// (then point is the query itself and the distance 0).
struct NearestPoint {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  double distance_squared = 0;
  bool inside = true;
};

// Internal linkage: each user's copy is called directly or inlined, never through the library's PLT.
namespace {

inline double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Closest point of segment [a, b] to x.
inline Eigen::Vector2d on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                  const Eigen::Vector2d& x) {
  const Eigen::Vector2d e = b - a;
  const double ee = e.squaredNorm();
  if (ee == 0) return a;
  return a + std::clamp((x - a).dot(e) / ee, 0.0, 1.0) * e;
}

// By looking at every edge (1 vertex: a point, 2: a segment).
inline NearestPoint nearest_on_polygon(const Eigen::Vector2d* v, std::size_t n, const Eigen::Vector2d& x) {
  NearestPoint best;
  if (n >= 3) {
    bool inside = true;
    for (std::size_t i = 0; i < n && inside; ++i)
      inside = cross(v[i + 1 == n ? 0 : i + 1] - v[i], x - v[i]) >= 0;
    if (inside) return {x, 0.0, true};
  }
  best.inside = false;
  best.distance_squared = std::numeric_limits<double>::infinity();
  const std::size_t edges = n == 1 ? 1 : n;
  for (std::size_t i = 0; i < edges; ++i) {
    const Eigen::Vector2d p = on_segment(v[i], v[i + 1 >= n ? 0 : i + 1], x);
    const double d2 = (p - x).squaredNorm();
    if (d2 < best.distance_squared) {
      best.distance_squared = d2;
      best.point = p;
    }
  }
  if (best.distance_squared == 0) best.inside = true;
  return best;
}

// The same for n >= 3, walking from edge `j` (vertex j -> j + 1, 0 <= j < n) towards the nearest
// feature: on each edge the foot of x tells on which side the nearest point lies, and the walk
// stops where the optimality condition holds (x − c in the normal cone at c: the foot on an edge
// that x lies outside of, or a vertex between its two edges' perpendiculars), so the answer does
// not depend on the start, which only sets the cost (one edge when it is the nearest). The foot
// is computed as on_segment does, so that the point is the one nearest_on_polygon finds. A walk
// that cannot conclude (x inside the polygon, a zero-length edge) looks at every edge.
inline NearestPoint nearest_from_edge(const Eigen::Vector2d* v, int n, const Eigen::Vector2d& x, int j) {
  for (int steps = 0; steps < n; ++steps) {
    const int k = j + 1 == n ? 0 : j + 1;
    const Eigen::Vector2d e = v[k] - v[j];
    const Eigen::Vector2d r = x - v[j];
    const double along = r.dot(e), ee = e.squaredNorm();
    if (along < 0) {  // before vertex j: it, or an earlier edge
      const int i = j == 0 ? n - 1 : j - 1;
      if (r.dot(v[j] - v[i]) >= 0) {
        const double d2 = r.squaredNorm();
        return {v[j], d2, d2 == 0};
      }
      j = i;
      continue;
    }
    if (along > ee) {  // beyond vertex k: it, or a later edge
      const int m = k + 1 == n ? 0 : k + 1;
      const Eigen::Vector2d rk = x - v[k];
      if (rk.dot(v[m] - v[k]) <= 0) {
        const double d2 = rk.squaredNorm();
        return {v[k], d2, d2 == 0};
      }
      j = k;
      continue;
    }
    if (ee == 0 || cross(e, r) > 0) break;  // a point edge, or x inside the edge's line
    const Eigen::Vector2d p = v[j] + (along / ee) * e;
    const double d2 = (p - x).squaredNorm();
    return {p, d2, d2 == 0};
  }
  return nearest_on_polygon(v, static_cast<std::size_t>(n), x);
}

}  // namespace
}  // namespace kg::numerics
