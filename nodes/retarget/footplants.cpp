// Footplant constraints (footplants.hpp): detected plants as fixed or floor constraints.
#include "kg/retarget/footplants.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace kg::retarget {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

std::function<double(const PointRef&, int)> plant_height_scale(const Target& target, double fps) {
  if (!(fps > 0) || !std::isfinite(fps))
    throw std::invalid_argument("plant height scale: fps must be positive");
  return
      [target, fps](const PointRef& point, int frame) { return height_factor(target, point, frame / fps); };
}

const char* to_string(PlantFlavour flavour) {
  return flavour == PlantFlavour::Fixed ? "fixed" : "floor";
}

void PlantConstraintOptions::validate() const {
  options::require(options::positive(weight), "PlantConstraintOptions", "weight", weight, "> 0 and finite");
}

ConstraintSet footplant_constraints(const motion::FootplantDetection& d, int frames,
                                    const PlantConstraintOptions& o) {
  o.validate();
  auto scale_at = [&](const PointRef& point, int f) {
    if (!o.height_scale) return 1.0;
    const double s = o.height_scale(point, f);
    if (!(s > 0) || !std::isfinite(s))
      throw std::invalid_argument("footplant constraints: height scale " + std::to_string(s) + " at frame " +
                                  std::to_string(f) + " (expected > 0)");
    return s;
  };
  auto on_target = [&](const PointRef& point, double height, int f) {
    return d.floor + scale_at(point, f) * (height - d.floor);
  };
  // A constraint whose target moves over its samples gets per-sample params, else one set.
  auto set_params = [](Constraint& c, std::vector<std::vector<double>> per_sample) {
    const bool constant = std::all_of(per_sample.begin(), per_sample.end(),
                                      [&](const auto& p) { return p == per_sample.front(); });
    if (constant && !per_sample.empty()) {
      c.params = per_sample.front();
      return;
    }
    c.params = per_sample.empty() ? std::vector<double>{} : per_sample.front();
    for (std::size_t i = 0; i < per_sample.size(); ++i) c.samples[i].params = std::move(per_sample[i]);
  };

  ConstraintSet set;
  std::vector<int> numbers(d.points.size(), 0);
  for (const motion::Footplant& p : d.plants) {
    const motion::PlantPoint& pt = d.points[static_cast<std::size_t>(p.point)];
    const std::string label =
        pt.name + " plant " + std::to_string(++numbers[static_cast<std::size_t>(p.point)]);
    Constraint pos;
    pos.kind = "position";
    pos.label = label;
    pos.points = {pt.point};
    pos.weight = o.weight;
    std::vector<std::vector<double>> targets;
    for (int f = p.first_frame; f <= p.last_frame; ++f) {
      pos.samples.push_back({.frames = {f}});
      const double y = on_target(pt.point, p.mean.y(), f);
      if (o.flavour == PlantFlavour::Fixed)
        targets.push_back({p.mean.x(), y, p.mean.z(), 1, 1, 1});
      else
        targets.push_back({0, y, 0, 0, 1, 0});
    }
    set_params(pos, std::move(targets));
    set.constraints.push_back(std::move(pos));
    if (o.flavour == PlantFlavour::Floor && p.last_frame > p.first_frame) {
      Constraint skid;
      skid.kind = "same_place";
      skid.label = label + " non-skid";
      skid.points = {pt.point, pt.point};
      skid.params = {1, 0, 1};
      // The chain's small per-row residuals add up along a long plant (an actor standing for
      // seconds): rows weighted by the square root of its length keep the whole plant's drift
      // as small as one row's.
      skid.weight = o.weight * std::sqrt(static_cast<double>(p.last_frame - p.first_frame));
      for (int f = p.first_frame; f < p.last_frame; ++f) skid.samples.push_back({.frames = {f, f + 1}});
      set.constraints.push_back(std::move(skid));
    }
  }
  if (o.above_floor && frames > 0)
    for (const motion::PlantPoint& pt : d.points) {
      Constraint above;
      above.kind = "region";
      above.label = pt.name + " above floor";
      above.points = {pt.point};
      above.weight = o.weight;
      std::vector<std::vector<double>> bounds;
      for (int f = 0; f < frames; ++f) {
        above.samples.push_back({.frames = {f}});
        double low = d.floor;
        if (d.floor_estimated && f < static_cast<int>(pt.heights.size()))
          low = std::min(low, on_target(pt.point, pt.heights[static_cast<std::size_t>(f)], f));
        bounds.push_back({-kInf, low, -kInf, kInf, kInf, kInf});
      }
      set_params(above, std::move(bounds));
      set.constraints.push_back(std::move(above));
    }
  return set;
}

}  // namespace kg::retarget
