// Footplant constraints (Gleicher 1998 §3.5, §7.1): the plants motion::detect_footplants finds
// (kg/motion/footplants.hpp), turned into constraints in either of the paper's flavours: fixed
// positions, or floor height plus non-skid only (the solver may move the plant).
//
//   motion::FootplantDetection d = motion::detect_footplants(walk, {});
//   ConstraintSet c = footplant_constraints(d, walk.frame_count(), {.flavour = PlantFlavour::Floor});
#pragma once

#include <functional>

#include "kg/motion/footplants.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

enum class PlantFlavour {
  Fixed,  // position (all axes) at the plant's mean position, every frame of the plant
  Floor,  // position on the up axis only at the plant's mean height, every frame, and same_place
          // on the horizontal axes between consecutive frames (non-skid; the place is free)
};
const char* to_string(PlantFlavour flavour);  // "fixed", "floor"

struct PlantConstraintOptions {
  PlantFlavour flavour = PlantFlavour::Fixed;
  // Also a region constraint keeping every detected point at or above the floor at every frame.
  // With an estimated floor, a frame whose source point lies below that estimate (captured
  // floors slope by centimetres) bounds the point at its own source height instead: the source's
  // contact with its floor is kept, never lifted to a level plane it did not walk on.
  bool above_floor = false;
  double weight = 1.0;
  // Moving the plants onto a character of another size: at frame f a point's height above the
  // floor is multiplied by height_scale(point, f) (> 0; plant_height_scale below: a smaller foot
  // rests lower on the floor), for plant heights and the source-height floor bounds alike.
  // Horizontal plant positions stay where the source had them (the paper's fixed footprints).
  // Empty: 1.
  std::function<double(const PointRef& point, int frame)> height_scale{};
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// height_scale for plants moved onto `target`: height_factor (target.hpp) at frame / fps seconds.
std::function<double(const PointRef&, int)> plant_height_scale(const Target& target, double fps);

// Constraints labelled "<point> plant <n>" (n from 1 per point) and "<point> above floor".
ConstraintSet footplant_constraints(const motion::FootplantDetection& detection, int frames,
                                    const PlantConstraintOptions& options);

}  // namespace kg::retarget
