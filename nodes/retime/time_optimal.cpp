#include "kg/retime/time_optimal.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/retime/retimer.hpp"

namespace kg::retime {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The part of convex polygon `poly` where n·x <= d (Sutherland-Hodgman against one half-plane).
Polygon clip(const Polygon& poly, const Eigen::Vector2d& n, double d) {
  Polygon out;
  const std::size_t count = poly.size();
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % count];
    const double da = n.dot(a) - d, db = n.dot(b) - d;
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push_back(a + (b - a) * (da / (da - db)));
    if (count == 1) break;
  }
  return out;
}

// The admissible set of one frame as a polygon of at least 3 vertices.
Polygon admissible(const Polygon& hull, double fps, double point_tolerance) {
  if (hull.size() >= 3) return hull;
  // A point or a segment: a box around it (see the header).
  double a_lo = kInf, a_hi = -kInf, b_lo = kInf, b_hi = -kInf;
  for (const Eigen::Vector2d& v : hull) {
    a_lo = std::min(a_lo, v.x()), a_hi = std::max(a_hi, v.x());
    b_lo = std::min(b_lo, v.y()), b_hi = std::max(b_hi, v.y());
  }
  const double db = point_tolerance * std::max(b_hi, 1e-3);
  const double da = db * fps / 2;
  b_lo = std::max(0.0, b_lo - db);
  return {{a_lo - da, b_lo}, {a_hi + da, b_lo}, {a_hi + da, b_hi + db}, {a_lo - da, b_hi + db}};
}

// The frame's admissible (a, b) whose next-frame speed b + 2a/fps lies in [lo, hi].
Polygon reaching(const Polygon& poly, double fps, double lo, double hi) {
  const double step = 2 / fps;
  Polygon p = clip(poly, Eigen::Vector2d(step, 1), hi);
  if (lo > -kInf) p = clip(p, Eigen::Vector2d(-step, -1), -lo);
  return p;
}

}  // namespace

void TimeOptimalOptions::validate() const {
  using options::require;
  const char* o = "TimeOptimalOptions";
  require(options::non_negative(point_tolerance), o, "point_tolerance", point_tolerance, ">= 0 and finite");
  require(options::positive(knot_spacing), o, "knot_spacing", knot_spacing,
          "> 0 and finite (output seconds)");
}

TimeOptimalResult time_optimal(const std::vector<Polygon>& hulls, double fps,
                               const TimeOptimalOptions& options) {
  options.validate();
  const int frames = static_cast<int>(hulls.size());
  if (frames < 2)
    throw std::invalid_argument("time-optimal retiming: " + std::to_string(frames) +
                                " frames (expected >= 2)");
  if (!(fps > 0) || !std::isfinite(fps))
    throw std::invalid_argument("time-optimal retiming: fps must be > 0");
  std::vector<Polygon> sets(static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    if (hulls[static_cast<std::size_t>(i)].empty())
      throw std::invalid_argument("time-optimal retiming: frame " + std::to_string(i) + " has an empty hull");
    // ṗ² >= 0 always.
    sets[static_cast<std::size_t>(i)] =
        clip(admissible(hulls[static_cast<std::size_t>(i)], fps, options.point_tolerance),
             Eigen::Vector2d(0, -1), 0);
  }

  TimeOptimalResult result;
  // Backward pass: controllable ṗ² ranges.
  std::vector<double> lo(static_cast<std::size_t>(frames)), hi(static_cast<std::size_t>(frames));
  for (int i = frames - 1; i >= 0; --i) {
    const Polygon p =
        i == frames - 1 ? sets.back()
                        : reaching(sets[static_cast<std::size_t>(i)], fps,
                                   lo[static_cast<std::size_t>(i + 1)], hi[static_cast<std::size_t>(i + 1)]);
    if (p.empty()) {
      result.blocking_frame = i;
      result.message = "no playback speed at source frame " + std::to_string(i) +
                       " stays inside its hull and can reach the speeds frame " + std::to_string(i + 1) +
                       " allows: no timing of this path is feasible";
      return result;
    }
    double l = kInf, h = -kInf;
    for (const Eigen::Vector2d& v : p) l = std::min(l, v.y()), h = std::max(h, v.y());
    lo[static_cast<std::size_t>(i)] = l, hi[static_cast<std::size_t>(i)] = h;
  }
  // Forward pass: as fast as every frame allows.
  result.pdot_squared.resize(static_cast<std::size_t>(frames));
  result.output_times.resize(static_cast<std::size_t>(frames));
  double b = hi[0];
  for (int i = 0; i + 1 < frames; ++i) {
    result.pdot_squared[static_cast<std::size_t>(i)] = b;
    const Polygon p = reaching(sets[static_cast<std::size_t>(i)], fps, lo[static_cast<std::size_t>(i + 1)],
                               hi[static_cast<std::size_t>(i + 1)]);
    // The largest a on the line ṗ² = b inside p (p contains such points: b is controllable).
    double a_max = -kInf;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const Eigen::Vector2d& u = p[k];
      const Eigen::Vector2d& v = p[(k + 1) % p.size()];
      if (std::abs(u.y() - b) <= 1e-12 * std::max(1.0, b)) a_max = std::max(a_max, u.x());
      if ((u.y() - b) * (v.y() - b) < 0)
        a_max = std::max(a_max, u.x() + (v.x() - u.x()) * (b - u.y()) / (v.y() - u.y()));
    }
    if (a_max == -kInf) {  // rounding at a vertex: take the nearest vertex's a
      double best = kInf;
      for (const Eigen::Vector2d& v : p)
        if (std::abs(v.y() - b) < best) best = std::abs(v.y() - b), a_max = v.x();
    }
    b = std::clamp(b + 2 * a_max / fps, lo[static_cast<std::size_t>(i + 1)],
                   hi[static_cast<std::size_t>(i + 1)]);
  }
  result.pdot_squared.back() = b;
  // Output time of each frame: dt = dp / ṗ with ṗ averaged over the frame interval.
  double t = 0;
  for (int i = 0; i < frames; ++i) {
    if (i > 0) {
      const double v = std::sqrt(result.pdot_squared[static_cast<std::size_t>(i - 1)]) +
                       std::sqrt(result.pdot_squared[static_cast<std::size_t>(i)]);
      if (!(v > 0)) {
        result.blocking_frame = i;
        result.message = "the time-optimal playback stops between source frames " + std::to_string(i - 1) +
                         " and " + std::to_string(i) + " (both at zero speed): no finite duration";
        return result;
      }
      t += 2 / (fps * v);
    }
    result.output_times[static_cast<std::size_t>(i)] = t;
  }
  result.duration = t;
  result.feasible = true;
  std::vector<double> source_times(static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) source_times[static_cast<std::size_t>(i)] = i / fps;
  const double wanted = std::ceil(t / options.knot_spacing - 1e-9);
  if (!(wanted <= kMaxSegments)) {
    result.feasible = false;
    result.message = "the time-optimal playback lasts " + std::to_string(t) + " s, more than " +
                     std::to_string(kMaxSegments) + " knots of " + std::to_string(options.knot_spacing) +
                     " s: playback nearly stops somewhere";
    return result;
  }
  const int segments = std::max(1, static_cast<int>(wanted));
  result.warp = fit_warp(result.output_times, source_times, segments);
  if (!result.warp.strictly_increasing()) {
    result.feasible = false;
    result.message = "the time-optimal profile (" + std::to_string(t) +
                     " s) has no strictly increasing spline fit with knots every " +
                     std::to_string(t / segments) + " s: playback nearly stops somewhere";
    return result;
  }
  result.message = "shortest feasible duration " + std::to_string(t) + " s";
  return result;
}

}  // namespace kg::retime
