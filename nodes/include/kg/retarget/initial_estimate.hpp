// The initial estimate m1 of a retargeting (Gleicher 1998, §3.8 and step 2 of §4): the source
// motion on the target skeleton with its root translation scaled by the target's overall scale
// and recentred by a smooth per-frame translation that brings the constraints as close as a
// whole-body shift can.
//
//   1. Scale (scale_translation): root position channels p_f become p'_0 = s_0 p_0,
//      p'_f = p'_{f-1} + s_f (p_f - p_{f-1}), s_f = target.overall_scale(f / fps): each frame's
//      change of translation scaled by that frame's scale and summed (§5; with a constant scale
//      that is s p). Position channels of other joints (offsets given as channels, e.g. Bandai)
//      are multiplied by their joint's factor (Target::joint_factors) at that frame.
//   2. Displacements (constraint_displacements): every constraint of character 0 sampled at one
//      instant is evaluated on the scaled motion on the target (skeleton_at per frame when
//      morphing). A whole-body shift d moves every point by d, so a row r changes by G d with
//      G = the sum of its point derivatives; a row whose G lies along one world axis a fixes
//      that axis, and needs d_a = -r / G_a. Per frame and axis: the mean of the equality rows'
//      d_a (the paper's average of displacements); with none, the violated inequality rows
//      (r < 0; a floor a foot sinks through), the largest push when they agree in sign, else
//      their mean. Rows along no single axis, rows of two-instant samples (same_place: it fixes
//      no place), rows of channel constraints and of character 1 fix nothing here.
//      E.g. position [x y z 1 0 1] fixes X and Z; region "above the floor" fixes Y when violated.
//   3. fill_gaps: per axis, linear interpolation over frames without a displacement, held
//      before the first and after the last; an axis never fixed gets 0.
//   4. smooth_zero_phase: a Gaussian (sigma in frames, truncated at 4 sigma; symmetric, so
//      zero-phase), ends extended by point reflection so a steady ramp (fixed footprints of a
//      shorter stride) passes unchanged. Default sigma 0.15 s: it keeps 17 % of a 2 Hz ripple
//      (the step-by-step staircase of footplant displacements) and under 0.3 % at 3.75 Hz (the
//      shortest period keys 4 frames apart at 30 Hz can form), so the shift adds nothing the
//      displacement map could not; slower trends pass.
//   5. The shift (world metres) is added to the root position channels (file coordinates:
//      file_to_world^T d); a world axis no root position channel can express is reported.
//
//   InitialEstimate m1 = initial_estimate(source, target, &constraints, finder, {});
//   m1.motion.skeleton == target.skeleton;   m1.shift.row(f) is what frame f was moved by.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

struct InitialEstimateOptions {
  double smooth_seconds = 0.15;  // Gaussian sigma of the low-pass on the added shift; 0: none
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

struct InitialEstimate {
  motion::Motion motion;      // m1: skeleton = target.skeleton, same frames, fps and name
  std::vector<double> scale;  // overall scale per frame
  // frames x 3, world metres: the averaged displacement per frame, NaN where nothing fixed the
  // axis in that frame; then the shift actually added (interpolated and smoothed).
  Eigen::MatrixXd raw_shift;
  Eigen::MatrixXd shift;
  std::array<bool, 3> axes_fixed{false, false, false};  // world axes some row fixed
  int constrained_frames = 0;                           // frames with a displacement on some axis
  int rows_used = 0;                                    // constraint rows that gave a displacement
  int rows_ignored = 0;                                 // rows that fix no single axis (see step 2)
  std::vector<std::string> notes;
};

// Step 1. `scales` (not null) gets s_f per frame. The result keeps source's skeleton.
motion::Motion scale_translation(const motion::Motion& source, const Target& target,
                                 std::vector<double>* scales = nullptr);

// Step 2 on `scaled` (the result of step 1, still on the source skeleton; evaluated on the
// target). Throws std::invalid_argument naming the constraint for an unknown kind, one the kind
// refuses, or frames or joints outside the motion. `rows_used` / `rows_ignored` when not null.
Eigen::MatrixXd constraint_displacements(const motion::Motion& scaled, const Target& target,
                                         const ConstraintSet& constraints, const KindFinder& kinds,
                                         int* rows_used = nullptr, int* rows_ignored = nullptr);

// Step 3: per column, NaN entries interpolated linearly, held at the ends; all-NaN columns 0.
Eigen::MatrixXd fill_gaps(const Eigen::MatrixXd& raw);

// Step 4: per column, Gaussian of `sigma_frames` (<= 0: a copy), point-reflected ends.
Eigen::MatrixXd smooth_zero_phase(const Eigen::MatrixXd& signal, double sigma_frames);

// Steps 1-5. `constraints` may be null (scaling only). Throws as the steps do, and
// std::invalid_argument when the target's source skeleton is not of the motion's structure.
InitialEstimate initial_estimate(const motion::Motion& source, const Target& target,
                                 const ConstraintSet* constraints, const KindFinder& kinds,
                                 const InitialEstimateOptions& options = {});

}  // namespace kg::retarget
