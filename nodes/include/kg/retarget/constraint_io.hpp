// Constraint sets from YAML files (joints named, not numbered), joint limits from a skeleton's
// channel limits (ASF `limits`) or from YAML, merging sets, and the constraint nodes.
//
// Format (version 1). Lengths in metres, angles of `params` in radians, `limits:` in degrees
// (rotation channels; position channels in metres), frames 0-based. Unknown keys are errors.
//
//   version: 1
//   doc: "footplants and a hand-hold of clip 07_05"   # optional, for people
//   constraints:
//     - kind: position                  # a built-in kind (constraint_kinds.hpp) or a plugin's;
//                                       # a plugin kind passes unchecked here, its params as given
//       label: "left toe on the box"    # optional; default "<kind> <index>"
//       relation: equal                 # equal (default) | at_least | at_most
//       points:                         # each {joint, offset, end_site, character, frame_offset}
//         - {joint: LeftToeBase, offset: [0, 0, 0.05]}   # offset in the joint's frame, metres
//         # end_site: true uses the joint's (first) End Site as offset; character: 0 | 1;
//         # frame_offset: k reads the point k frames after the sample frame (a lag)
//       channels: ["LeftLeg.Xrotation"] # or {joint: LeftLeg, channel: Xrotation, character: 0}
//       params: [0.1, 0, 0.3, 1, 1, 1]
//       frames: [40, 55]                # inclusive range, sampled every frame; or
//       # at_frames: [3, 9, 12]         # a list of frames; or, in seconds (rounded to frames
//       # times: [1.33, 1.83]           # of the first character's motion), a range or
//       # at_times: [0.5, 1.0]          # a list. Exactly one of the four.
//       weight: 1.0                     # optional row scale
//     - kind: same_place                # one point given: it is read at consecutive sample
//       points: [{joint: LeftToeBase, end_site: true}]  # frames (f, next f): non-skid
//       params: [1, 0, 1]
//       frames: [40, 55]
//   limits:                             # joint-name regular expression (RE2, whole name):
//     "[lr](femur|tibia)": {Xrotation: [-160, 20]}      #   {channel: [min, max]}
//     "lfoot": {Xrotation: [-45, .inf]}                 # .inf / -.inf leave a side free
//   limits_character: 0                 # optional: the character `limits` apply to
//
// `limits` patterns are RE2 syntax (kg/base/pattern.hpp, https://github.com/google/re2/wiki/Syntax:
// no backreferences or lookaround), at most Pattern::kMaxLength bytes.
// Every error names file:line:column: an unknown joint with the nearest name, a frame range out
// of the clip or reversed, an unknown key with the nearest allowed one, a built-in kind's check
// failing (wrong param count, ...), a bad regular expression (a short excerpt of it).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"

namespace kg::retarget {

inline constexpr int kConstraintFormatVersion = 1;

// `characters[c]` is character c's motion (its skeleton resolves joint names, its frame count
// bounds frames, the first one's fps turns times into frames). Throws kg::Error with
// file:line:column. Built-in kinds are checked (ConstraintKind::check); others pass through.
ConstraintSet read_constraints_file(const std::string& path, std::span<const motion::Motion> characters);
ConstraintSet read_constraints_string(const std::string& text, const std::string& file_name,
                                      std::span<const motion::Motion> characters);

// One parameter_range constraint per channel of `skeleton` with a finite limit (Channel::min or
// max), sampled at every frame 0..frames-1, labelled "limit Joint.Channel", on `character`.
ConstraintSet joint_limit_constraints(const motion::Skeleton& skeleton, int character, int frames);

// Appends `more`'s constraints to `into`.
void merge_constraints(ConstraintSet& into, const ConstraintSet& more);

}  // namespace kg::retarget
