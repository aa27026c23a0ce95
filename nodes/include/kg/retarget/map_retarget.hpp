// Retargeting onto a character of another structure through a skeleton map (Gleicher 1998 §8):
// the source is first adapted to a figure of its own structure with the target's proportions,
// then the target's own degrees of freedom are solved so that each mapped target feature follows
// its adapted source feature, in least squares where the target cannot follow exactly (the
// paper's "best matching motion").
//
//   motion::Motion a = adapt_clip(clip, map, target_skeleton, &notes);     // on the adapted figure
//   ConstraintSet features = feature_constraints(pairs, offsets, a, target_skeleton);
//   motion::Motion start = placed_rest_pose(map, offsets_of_pelvis, a, target_ptr);
//   PerFrameIkResult baseline = solve_per_frame_ik(start, features, kinds);  // per_frame_ik.hpp
//
// Units: metres and radians; world +Y up (file_to_world applied on both skeletons).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/per_frame_ik.hpp"
#include "kg/retarget/skeleton_map.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

// The adapted figure (§8's first step): the source's structure with the target's proportions,
// as a Target (target.hpp) on the source skeleton, so the retargeting machinery of the source's
// own structure (scale_translation, footplants, the spacetime solver) adapts the clip to it.
// Rest-pose distances between the map's role joints decide it:
//   - limb segments (thigh hip -> knee, shin knee -> ankle, foot ankle -> toe; upper arm
//     shoulder -> elbow, forearm elbow -> wrist) are scaled to the target's lengths, keeping the
//     source's directions (its joint angles are expressed against them); the joints below the
//     last one (toes, End Sites, the hand) take the last segment's factor;
//   - the trunk's connections (pelvis -> chest, chest -> head, pelvis -> each hip, chest -> each
//     shoulder) take the target's rest vectors, turned from the target's body frame into the
//     source's (body_frame: left, up, forward), so the hips, shoulders and head sit on the trunk
//     where the target's do; joints two connections share (one joint carrying both hips) stay,
//     and the rest of the connection makes up the difference; the head's subtree takes the neck's
//     length ratio;
//   - every other joint (and every joint of a chain only one side has) the overall factor: the
//     ratio of the legs' lengths (hip -> knee -> ankle, both legs), which a rest pose that does not
//     stand leaves alone; without legs on both, the ratio of the rest hip heights
//     (rest_hip_height), else 1.
// Each decision goes to `notes` (when not null) with its lengths. Throws std::invalid_argument when
// a map joint is outside its skeleton, or the trunk's connections are asked for and a side's
// chains give no left (body_frame).
Target adapted_target(const SkeletonMap& map, std::shared_ptr<const motion::Skeleton> source,
                      const motion::Skeleton& target, std::vector<std::string>* notes = nullptr);

// The clip on the adapted figure: adapted_target, then scale_translation (initial_estimate.hpp)
// with the result on the figure's skeleton (same joints and channels as the clip's).
motion::Motion adapt_clip(const motion::Motion& clip, const SkeletonMap& map, const motion::Skeleton& target,
                          std::vector<std::string>* notes = nullptr);

// The constraints that make the target follow the adapted source, one per feature pair and,
// per frame of `adapted` (on the adapted figure: same joints as map.source), one sample whose
// params hold that frame's source feature in the world:
//   position     kind "position", the target point, params [x y z 1 1 1];
//   direction    kind "orientation", points [from, to] on the target, params the unit source
//                direction;
//   orientation  two "orientation" constraints on unit segments along the target joint's local
//                X and Y axes, params the source joint's world rotation times offsets[i]
//                (rest_offsets) applied to those axes: together they fix the joint's rotation.
// A pair's weight becomes the constraint's; a soft pair (not hard) gives soft constraints
// (Constraint::soft), a hard pair required ones weighted kHardWeight times its weight: the
// per-frame IK minimises every row in one objective, so a hard row then misses by about 1e-6 of
// what the soft rows would pull it away by. Labels are the pair names (".x"/".y" added for
// orientation pairs). `offsets` has pairs.size() entries. Character 0 is the target.
inline constexpr double kHardWeight = 1000;
ConstraintSet feature_constraints(const std::vector<FeaturePair>& pairs,
                                  const std::vector<Eigen::Matrix3d>& offsets, const motion::Motion& adapted,
                                  const motion::Skeleton& target);

// The target's rest pose at every frame of `adapted` (its fps and name), with its root moved so
// that the target's pelvis (map.target.chains.pelvis) is where the adapted source's pelvis is and
// turned as it is, times `pelvis_offset` (the pelvis orientation pair's rest offset, identity
// when none). Joints between the root and the pelvis stay at rest. A root without position
// channels keeps its place; one without three rotation channels keeps its rotation (said in
// `notes`). The starting point of the feature solves: every channel no feature drives stays here.
// Throws std::invalid_argument when either side has no pelvis.
motion::Motion placed_rest_pose(const SkeletonMap& map, const Eigen::Matrix3d& pelvis_offset,
                                const motion::Motion& adapted, std::shared_ptr<const motion::Skeleton> target,
                                std::vector<std::string>* notes = nullptr);

// The whole solve of §8 on one clip (footplants on the target's feet are not carried yet).
struct MapRetargetOptions {
  double smooth_seconds = 1.0 / 30;  // Gaussian sigma low-passing the IK into m1 (> 0)
  PerFrameIkOptions ik{.warm_start = true};
  SpacetimeOptions spacetime{};
  int frames_per_key = 4;  // the displacement's key spacing, every channel (>= 1)
  // Throws std::invalid_argument naming the field, its value and its range.
  void validate() const;
};

struct MapRetargetResult {
  motion::Motion adapted;  // the source on the adapted figure (its structure, the target's proportions)
  std::vector<FeaturePair> pairs;
  ConstraintSet constraints;    // the features (soft unless hard), then the target's joint limits
  int feature_constraints = 0;  // how many of `constraints` are features
  PerFrameIkResult baseline;    // the per-frame IK on the same map: the baseline and m1's source
  SpacetimeResult solve;        // the spacetime solve from m1; solve.motions[0] is the result
  std::vector<std::string> notes;
  double seconds_adapt = 0, seconds_ik = 0, seconds_spacetime = 0;  // wall time of each stage
  const motion::Motion& motion() const { return solve.motions.front(); }
};

// adapted_target and scale_translation give the adapted clip; feature_constraints with the
// target's joint limits (joint_limit_constraints, weighted kHardWeight: required beside soft rows)
// the constraints; placed_rest_pose the start of the per-frame IK (warm-started), whose result,
// low-passed (smooth_seconds), is the initial estimate m1 of the spacetime solve over the
// target's own channels: the best matching motion of §8 by a displacement smooth at the key
// spacing. Throws std::invalid_argument for bad options, a map that does not fit the skeletons,
// or a map without a pelvis on both sides.
MapRetargetResult retarget_onto(const motion::Motion& clip, const SkeletonMap& map,
                                std::shared_ptr<const motion::Skeleton> target, const KindFinder& kinds,
                                const MapRetargetOptions& options = {});

}  // namespace kg::retarget
