// Holds between two characters (Gleicher 1998 §7.3: "the hands of the two characters must
// remain connected"): spans of frames during which a point of character 0 and a point of
// character 1 stay within a distance of each other (a hand-hold of two dancers), found on the
// source motions and emitted as `distance` constraints that keep, at every frame of the span,
// the distance the source had. A retargeting that changes one dancer's size then has to bring
// the hands together as they were, moving the other dancer where it may.
//
// Detection, per pair (a, b) of points_a x points_b: a span starts where |a - b| <= max_distance
// and lasts while |a - b| <= max_distance * hysteresis; spans shorter than min_duration_s are
// dropped.
//
//   HoldDetection h = detect_holds(follow, lead, {.points_a = {"rHand"}, .points_b = {"lHand"}});
//   ConstraintSet set = hold_constraints(h);     // distance, points [a on 0, b on 1]
#pragma once

#include <string>
#include <vector>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/footplants.hpp"

namespace kg::retarget {

struct HoldOptions {
  // Points by the syntax of motion::FootplantOptions::points ("lHand", "lHand/end", "lHand[0 -0.08 0]")
  // on character 0 (points_a) and character 1 (points_b); every pair is tried.
  std::vector<std::string> points_a{};
  std::vector<std::string> points_b{};
  double max_distance = 0.15;   // m, to enter a hold
  double hysteresis = 1.25;     // leave at max_distance * hysteresis (>= 1)
  double min_duration_s = 0.2;  // shorter spans are dropped
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

struct HoldSpan {
  int point_a = 0, point_b = 0;  // indexes into HoldDetection::points_a / points_b
  int first_frame = 0;           // inclusive
  int last_frame = 0;            // inclusive
  std::vector<double> distance;  // m, the source's |a - b| at each frame of the span
};

struct HoldDetection {
  std::vector<motion::PlantPoint> points_a, points_b;  // PointRef::character 0 and 1
  std::vector<HoldSpan> holds;                         // by pair, then time
  double closest = 0;                                  // m, the smallest distance of any pair at any frame
};

// `a` and `b` must have the same frame count and rate. Throws std::invalid_argument for
// unknown joints (with the nearest name), empty point lists, mismatched or malformed motions
// (non-finite values: Motion::check) or options out of range.
HoldDetection detect_holds(const motion::Motion& a, const motion::Motion& b, const HoldOptions& options);

// One `distance` constraint per hold, labelled "<a> ~ <b> hold <n>", sampled at every frame of
// its span with that frame's source distance as the target.
ConstraintSet hold_constraints(const HoldDetection& detection, double weight = 1.0);

}  // namespace kg::retarget
