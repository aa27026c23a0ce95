// The character a motion is retargeted to (Gleicher 1998): the same structure as the source
// skeleton with other segment lengths, constant or changing over the clip (morphing, §5).
//
//   Target t = uniform_target(source_skeleton, 0.6);
//   std::shared_ptr<const Skeleton> s = t.skeleton_at(frame_time_seconds);
//   LoadedTarget file = load_target(source_skeleton, "short_legs.yaml");   // or .bvh / .asf
//
// A joint's length factor scales its offset from its parent (the segment from the parent joint
// to it) and its End Sites; the root's factor scales the root offset (a position, which the
// initial estimate scales alike). Joint axes, channels, limits, file_to_world and units stay the
// source's: the motion's values are expressed in them.
//
// Target YAML files (parse_target_yaml; every error names file:line:column):
//   version: 1
//   default: 1.0                    # factor for joints no pattern matches (> 0; default 1)
//   bones:                          # joint-name regex (the WHOLE name must match): factor
//     "[lr](Shin|Foot)": 0.7        # patterns are tried in file order, the first match wins
//     "abdomen|chest|neck": 1.2
// or `lengths:` instead of `bones:`: absolute lengths (metres, > 0) of the joints' offsets from
// their parents, directions kept; the joint's End Sites scale by the same ratio; unmatched
// joints take `default` as a factor. A matched joint whose source offset is zero cannot be given
// a length (an error). Or, for morphing:
//   version: 1
//   default: 1.0                    # for keys giving bones/lengths without their own default
//   morph:                          # keys at strictly increasing times (seconds, >= 0)
//     - {time: 0.0, scale: 1.0}
//     - time: 3.5
//       bones: {"l.*": 0.6}         # or scale: (uniform) or lengths:; `default:` allowed too
// Factors are interpolated linearly between keys and held before the first and after the last.
// Patterns are RE2 syntax (kg/base/pattern.hpp, https://github.com/google/re2/wiki/Syntax: no
// backreferences or lookaround), at most Pattern::kMaxLength bytes.
// Unknown keys, bad regular expressions, non-positive or non-finite numbers, a pattern matching
// no joint, a missing or wrong `version` are errors.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/skeleton.hpp"
#include "kg/retarget/constraints.hpp"

namespace kg::retarget {

struct Target {
  std::shared_ptr<const motion::Skeleton> source;  // the motion's own skeleton (not owned data)
  // The target's constant skeleton (for a morph: its state at time 0). Same joints, channels
  // and channel order as `source`; only offsets and end sites differ.
  std::shared_ptr<const motion::Skeleton> skeleton;
  // Morphing: per-joint length factors relative to `source`, keyed at times (seconds, strictly
  // increasing), interpolated linearly between keys and held outside. Empty: not morphing.
  std::vector<double> key_times{};
  std::vector<Eigen::VectorXd> key_factors{};  // each joint_count() long

  bool morphing() const { return !key_times.empty(); }
  // The target skeleton at time t (seconds): `skeleton` when not morphing (a new skeleton per
  // call when morphing: callers sampling every frame should keep it for the frame).
  std::shared_ptr<const motion::Skeleton> skeleton_at(double t) const;
  // Overall scale of the target against the source at time t (1 = same size): the ratio of
  // leg-and-spine heights, estimated for non-uniform scalings (§3.8).
  //
  // The estimate (rest_hip_height below): the height of the root above the lowest joint or End
  // Site of the source's rest pose (world +Y, file_to_world applied), on source and target,
  // measured between the same two points; for a standing figure that is the hip height, legs
  // plus pelvis. Why: what this scale multiplies is the root translation, and the root's height
  // above the floor and its stride are set by the legs and pelvis; the ratio keeps a rest-pose
  // figure's feet on the floor after scaling, and equals s exactly for a uniform scale s. When
  // that height is zero (a rest pose that does not stand, e.g. lying along X), the ratio of the
  // summed offset lengths along the same root-to-lowest-point chain is used instead.
  double overall_scale(double t) const;
  // Additive (issue 3): per-joint length factors against `source` at time t (joint_count()
  // entries): the interpolated key_factors when morphing, else |skeleton offset| / |source
  // offset| (1 where the source offset is zero). Joints with position channels (their offset
  // is a channel value, e.g. Bandai's) have those values scaled by this in the initial estimate.
  Eigen::VectorXd joint_factors(double t) const;
};

// `source` with every joint's offset and End Sites multiplied by factors[j] (joint_count()
// entries, each > 0 and finite; std::invalid_argument otherwise).
std::shared_ptr<const motion::Skeleton> scaled_skeleton(const motion::Skeleton& source,
                                                        const Eigen::VectorXd& factors);

// A uniform scale (> 0) of the whole source.
Target uniform_target(std::shared_ptr<const motion::Skeleton> source, double scale);
// Per-joint factors (joint_count() entries, > 0).
Target factor_target(std::shared_ptr<const motion::Skeleton> source, const Eigen::VectorXd& factors);
// Morphing: key_times strictly increasing, key_factors as many, each joint_count() long, > 0.
Target morph_target(std::shared_ptr<const motion::Skeleton> source, std::vector<double> key_times,
                    std::vector<Eigen::VectorXd> key_factors);

// Throws std::invalid_argument naming the first difference when `target` (read from `what`, a
// file name for messages) is not of the source's structure: joint count ("target skeleton has 31
// joints, source 43"), a name ("joint 12 is 'lhand' in the target, 'lwrist' in the source"), a
// parent, the channels of a joint (kinds in order), or its End Site count.
void check_same_structure(const motion::Skeleton& target, const motion::Skeleton& source,
                          const std::string& what = "target skeleton");

// The target whose offsets and End Sites are those of `other` (a skeleton of the same
// structure, metres; check_same_structure first); everything else stays the source's. Notes
// (differing joint axes, units) go to `notes` when not null.
Target skeleton_target(std::shared_ptr<const motion::Skeleton> source, const motion::Skeleton& other,
                       const std::string& what, std::vector<std::string>* notes = nullptr);

// Root height above the lowest rest-pose point (see Target::overall_scale), metres; `chain_end`
// gets that point's joint (-1 when the skeleton is empty).
double rest_hip_height(const motion::Skeleton& skeleton, int* chain_end = nullptr);

// What a target file gave.
struct LoadedTarget {
  Target target;
  std::string kind;                // "bones", "lengths", "morph", "skeleton"
  std::vector<std::string> notes;  // one line each, for the user (patterns and their joints...)
};

// A target YAML text (the format above); `path` names the file in messages (file:line:col).
// Throws kg::Error.
LoadedTarget parse_target_yaml(std::shared_ptr<const motion::Skeleton> source, std::string_view text,
                               const std::string& path);
// By extension (case-insensitive): .yaml/.yml (parse_target_yaml), .bvh (kg::io::import_bvh,
// units and up auto) or .asf (kg::io::read_asf, its declared units) as a skeleton_target.
// Throws kg::Error for an unreadable or malformed file, std::invalid_argument for another
// structure or an unknown extension.
LoadedTarget load_target(std::shared_ptr<const motion::Skeleton> source, const std::string& path);

// How much the height above the floor of `point` (on the source skeleton, resting on the floor:
// an ankle, a toe tip) scales on the target at time t: the length-weighted mean factor of the
// segments that hold it up, i.e. its own offset on its joint and every segment and End Site
// below its joint (an ankle rests on the foot and toes, a toe tip on its End Site); the overall
// scale when nothing lies below it.
double height_factor(const Target& target, const PointRef& point, double t);

// Constraints measured on the source character (points as offsets in source segments: a heel
// on the foot), moved onto the target: every point of `character` has its local offset scaled
// by its joint's factor, as End Sites are. On a morphing target each sample gets its own point
// offsets (Sample::locals), scaled by the factors at its frames' times (frame / fps, s); the
// constraint's points keep the offsets at time 0. Throws std::invalid_argument for a morphing
// target without a positive fps.
ConstraintSet constraints_on_target(const ConstraintSet& constraints, const Target& target, int character = 0,
                                    double fps = 0);

}  // namespace kg::retarget
