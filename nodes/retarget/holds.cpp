// Holds between two characters (holds.hpp).
#include "kg/retarget/holds.hpp"
#include "kg/base/option_check.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace kg::retarget {

void HoldOptions::validate() const {
  using options::require;
  const char* o = "HoldOptions";
  require(!points_a.empty(), o, "points_a", points_a, "at least one point (of character 0)");
  require(!points_b.empty(), o, "points_b", points_b, "at least one point (of character 1)");
  require(options::positive(max_distance), o, "max_distance", max_distance, "> 0 and finite (metres)");
  require(hysteresis >= 1 && std::isfinite(hysteresis), o, "hysteresis", hysteresis, ">= 1 and finite");
  require(options::non_negative(min_duration_s), o, "min_duration_s", min_duration_s,
          ">= 0 and finite (seconds)");
}

HoldDetection detect_holds(const motion::Motion& a, const motion::Motion& b, const HoldOptions& o) {
  if (!a.skeleton || !b.skeleton) throw std::invalid_argument("holds: a motion has no skeleton");
  a.check();
  b.check();
  if (a.frame_count() != b.frame_count() || std::abs(a.fps - b.fps) > 1e-9 * a.fps)
    throw std::invalid_argument("holds: the two motions differ in length or rate (" +
                                std::to_string(a.frame_count()) + " frames at " + std::to_string(a.fps) +
                                " Hz, " + std::to_string(b.frame_count()) + " at " + std::to_string(b.fps) +
                                " Hz): resample them alike");
  o.validate();
  HoldDetection d;
  for (const std::string& spec : o.points_a)
    d.points_a.push_back(motion::find_point(*a.skeleton, spec, 0, "holds"));
  for (const std::string& spec : o.points_b)
    d.points_b.push_back(motion::find_point(*b.skeleton, spec, 1, "holds"));
  const std::vector<Eigen::Vector3d> pa = motion::point_positions(a, d.points_a),
                                     pb = motion::point_positions(b, d.points_b);
  const int frames = a.frame_count();
  const int min_frames = std::max(1, static_cast<int>(std::ceil(o.min_duration_s * a.fps - 1e-9)));
  d.closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < d.points_a.size(); ++i)
    for (std::size_t j = 0; j < d.points_b.size(); ++j) {
      std::vector<double> dist(static_cast<std::size_t>(frames));
      for (int f = 0; f < frames; ++f) {
        dist[static_cast<std::size_t>(f)] = (pa[static_cast<std::size_t>(f) * d.points_a.size() + i] -
                                             pb[static_cast<std::size_t>(f) * d.points_b.size() + j])
                                                .norm();
        d.closest = std::min(d.closest, dist[static_cast<std::size_t>(f)]);
      }
      auto close = [&](int first, int last) {
        if (last - first + 1 < min_frames) return;
        d.holds.push_back({static_cast<int>(i), static_cast<int>(j), first, last,
                           std::vector<double>(dist.begin() + first, dist.begin() + last + 1)});
      };
      bool in = false;
      int start = 0;
      for (int f = 0; f < frames; ++f) {
        const double v = dist[static_cast<std::size_t>(f)];
        if (!in && v <= o.max_distance) {
          in = true;
          start = f;
        } else if (in && v > o.max_distance * o.hysteresis) {
          in = false;
          close(start, f - 1);
        }
      }
      if (in) close(start, frames - 1);
    }
  if (frames == 0) d.closest = 0;
  return d;
}

ConstraintSet hold_constraints(const HoldDetection& d, double weight) {
  if (!(weight > 0)) throw std::invalid_argument("hold constraints: weight must be positive");
  ConstraintSet set;
  std::vector<int> numbers(d.points_a.size() * d.points_b.size(), 0);
  for (const HoldSpan& h : d.holds) {
    const motion::PlantPoint& a = d.points_a[static_cast<std::size_t>(h.point_a)];
    const motion::PlantPoint& b = d.points_b[static_cast<std::size_t>(h.point_b)];
    const int n = ++numbers[static_cast<std::size_t>(h.point_a) * d.points_b.size() +
                            static_cast<std::size_t>(h.point_b)];
    Constraint c;
    c.kind = "distance";
    c.label = a.name + " ~ " + b.name + " hold " + std::to_string(n);
    c.points = {a.point, b.point};
    c.params = {h.distance.front()};
    c.weight = weight;
    for (int f = h.first_frame; f <= h.last_frame; ++f)
      c.samples.push_back(
          {.frames = {f, f}, .params = {h.distance[static_cast<std::size_t>(f - h.first_frame)]}});
    set.constraints.push_back(std::move(c));
  }
  return set;
}

}  // namespace kg::retarget
