// The seven built-in constraint kinds of Gleicher 1998 §3.5, the table the solvers look kinds up
// in (built-ins plus `kg.ConstraintKind` extensions from plugins), and evaluation helpers shared
// by the solver report, the per-frame IK baseline and the metrics.
//
// Built-in kinds (rows per sample; "ineq" rows want r >= 0, the others r = 0; residuals are
// unweighted: the solver multiplies by Constraint::weight):
//   parameter_range  channels >= 1, points 0. params [min, max] (either may be +-inf; relation
//                    must be equal): per channel, rows v - min >= 0 and max - v >= 0 for the
//                    finite bounds. params [value]: per channel v - value (equal), v - value >= 0
//                    (at_least), value - v >= 0 (at_most).
//   position         points 1. params [x y z mx my mz] (target, then a 0/1 mask of the world axes
//                    it fixes; [x y z] alone fixes all three): per masked axis p_i - t_i (equal),
//                    p_i - t_i >= 0 (at_least), t_i - p_i >= 0 (at_most).
//   region           points 1. params [minx miny minz maxx maxy maxz] (+-inf allowed, min <= max;
//                    relation must be equal): ineq rows p_i - min_i and max_i - p_i for finite
//                    bounds. "Above the floor": [-inf, floor, -inf, inf, inf, inf].
//   same_place       points 2 (usually the same point twice) read at two frames
//                    (Sample::frames = [fa, fb]). params [mx my mz] mask ([] = all axes; non-skid:
//                    [1 0 1]); relation equal: per masked axis p1_i - p0_i. The place itself is
//                    free.
//   follow_path      points [p, q] (q may be on the other character and read at another frame).
//                    params [ox oy oz] or [ox oy oz mx my mz] (offset, optional mask): per masked
//                    axis p_i - q_i - o_i, with relations as for position.
//   distance         points [p, q]. params [d] (metres, >= 0): one row |p - q| - d (equal),
//                    |p - q| - d >= 0 (at_least), d - |p - q| >= 0 (at_most). The norm is
//                    smoothed as sqrt(|p - q|^2 + 1e-12) so it stays differentiable at p = q.
//   orientation      points [p, q]. params [dx dy dz] (a direction, normalised here): equal, rows
//                    u - d with u = (q - p) / |q - p| (3 rows). params [dx dy dz a] with at_most:
//                    one ineq row u.d - cos(a) >= 0 (the angle between u and d at most a radians);
//                    at_least: cos(a) - u.d >= 0.
//
//   ConstraintKindTable kinds = kinds_for(set, ctx);          // throws naming unknown kinds
//   const ConstraintKind* kind = kinds.find("position");
//   PoseCache poses(motions);                                // FK of every frame, once
//   ViolationSummary v = summarize_violations(set, kinds, poses);
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraints.hpp"

namespace kg::retarget {

// Name -> kind. Holds shared ownership (a plugin's kind keeps its extension alive through the
// shared_ptr the registry handed out).
class ConstraintKindTable {
 public:
  // The seven built-in kinds.
  static ConstraintKindTable builtin();
  // Throws std::invalid_argument when a kind of that name is already present or kind is null.
  void add(std::shared_ptr<const ConstraintKind> kind);
  // Null when absent.
  const ConstraintKind* find(const std::string& name) const;
  std::shared_ptr<const ConstraintKind> find_shared(const std::string& name) const;
  std::vector<std::string> names() const;  // sorted

 private:
  std::map<std::string, std::shared_ptr<const ConstraintKind>> kinds_;
};

// A kind by name for solvers and estimators (a ConstraintKindTable's find, typically); null
// when unknown.
using KindFinder = std::function<const ConstraintKind*(const std::string& name)>;

// A kind by name among the kinds registered beside the built-ins (a registry's `kg.ConstraintKind`
// extensions, kg/retarget/nodes.hpp); null when absent.
using ConstraintKindLookup = std::function<std::shared_ptr<const ConstraintKind>(const std::string& name)>;

// builtin() plus every kind `set` names that is not built in, found through `lookup`. Throws
// std::invalid_argument "constraint 'label': unknown kind 'x' (known: a, b, ...; did you mean 'y'?)"
// for the first constraint whose kind is found nowhere, or when an extension's name() differs from
// the name it was registered under.
ConstraintKindTable kinds_for(const ConstraintSet& set, const ConstraintKindLookup& lookup);

// Calls kind->check on every constraint (kinds must all be in `kinds`, else as kinds_for throws).
void check_constraints(const ConstraintSet& set, const ConstraintKindTable& kinds);

// How far a residual row is from holding: |r| for an equality row, max(0, -r) for an inequality.
inline double row_violation(double residual, bool inequality) {
  return inequality ? (residual < 0 ? -residual : 0.0) : (residual < 0 ? -residual : residual);
}

// World transforms of every joint at every frame of each character's motion (computed once), to
// evaluate constraints without FK per sample. Holds copies of nothing but the transforms and a
// reference to `motions`, which must outlive the cache (not owned).
class PoseCache {
 public:
  // The skeleton of a character at a frame (a morphing target's); null keeps the motion's own.
  using SkeletonAt = std::function<std::shared_ptr<const motion::Skeleton>(int frame)>;
  // motions[c] is character c's motion on the skeleton constraints are evaluated against (the
  // target skeleton when measuring a retargeted result); skeleton_at[c], when given and not
  // null, replaces that skeleton frame by frame (morphing).
  explicit PoseCache(std::span<const motion::Motion> motions, std::span<const SkeletonAt> skeleton_at = {});
  int character_count() const { return static_cast<int>(motions_.size()); }
  int frame_count(int character) const;
  // World position of `point` at `frame`; throws std::out_of_range naming the character, joint
  // or frame when out of range.
  Eigen::Vector3d point(const PointRef& point, int frame) const;
  double value(const ChannelRef& channel, int frame) const;

 private:
  std::span<const motion::Motion> motions_;
  std::vector<std::vector<Eigen::Isometry3d>> world_;  // [character][frame * joints + joint]
};

// Residuals (unweighted) of one sample of `constraint`: the world points and values read from
// `poses` at the sample's frames, then kind.evaluate. `residual` is resized to kind.rows(). Throws
// std::out_of_range (with the label) for frames or joints outside the motions.
void evaluate_sample(const ConstraintKind& kind, const Constraint& constraint, const Sample& sample,
                     const PoseCache& poses, Eigen::VectorXd& residual);

// Worst and mean violation (row_violation) of one kind over all rows of all samples; mean over
// the rows that count: every equality row, and the inequality rows that are violated (r < 0).
// Units: metres for point kinds, the channel unit for parameter_range, unit-vector components
// (about radians when small) for orientation equality rows, cosines for its inequality row.
struct KindViolation {
  std::string kind;
  int rows = 0;           // rows evaluated (samples x rows per sample)
  int counted_rows = 0;   // rows in the mean
  int violated_rows = 0;  // rows violated by more than `tolerance`
  double worst = 0;
  double mean = 0;
  std::string worst_label;  // the constraint holding the worst row
  int worst_frame = -1;     // the first frame of that row's sample
};
struct ViolationSummary {
  std::vector<KindViolation> kinds;  // sorted by kind name, only kinds present in the set
  double worst() const;              // over all kinds, 0 when empty
  const KindViolation* find(const std::string& kind) const;
};
ViolationSummary summarize_violations(const ConstraintSet& set, const ConstraintKindTable& kinds,
                                      const PoseCache& poses, double tolerance = 1e-3);
// Convenience: builds the PoseCache of `motions` (one per character).
ViolationSummary summarize_violations(const ConstraintSet& set, const ConstraintKindTable& kinds,
                                      std::span<const motion::Motion> motions, double tolerance = 1e-3);

// Relation from its to_string text ("equal", "at_least", "at_most"); throws std::invalid_argument.
Relation relation_from_string(const std::string& text);

}  // namespace kg::retarget
