// A retargeting solved at one frame rate, written at another. The solve (spacetime.hpp) works at
// the paper's 30 Hz; the clip it adapts may be a 120 Hz capture. The result is the scaled source
// plus a displacement that is smooth in time (Gleicher 1998 §3.7: a cubic B-spline per channel,
// plus the initial estimate's low-passed shift), so it applies at any rate:
//
//   result(t) = scaled(source at the rate written)(t) + D(t),
//   D = result - scaled(source at the solve's rate), sampled at the solve's frames,
//
// where `scaled` is scale_translation (initial_estimate.hpp) and D(t) is the C2 cubic spline
// through D's samples (knots at every solve frame). A cubic B-spline with keys every k >= 2
// frames lies in that spline space, so away from the clip's first and last frames D(t) is the
// solve's own displacement; at every solve frame it is exact, so constraints the solve met hold
// there, and the frames between keep the source's own detail at the finer rate. Output frames
// past the solve's last frame (at most one solve frame) continue D along its end slope.
// Between solve frames the spline meets the constraints only as closely as the source moves like
// a spline there (a foot a capture lets jitter in its plant: 0.11 cm at 50 Hz from 16_15's 120);
// retarget.at_rate then holds the constraints at every frame written by per-frame IK
// (per_frame_ik.hpp), damped towards this result.
//
//   Motion at120 = resample(clip, 120), at30 = resample(clip, 30);   // the same clip
//   ResultAtRate r = result_at_rate(at120, at30, m1, solved, target);
//   r.result: 120 Hz on the target skeleton; r.initial: m1 at 120 Hz (for metrics)
#pragma once

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

struct ResultAtRate {
  motion::Motion result;   // the solve's result at `at_rate`'s frames (target skeleton)
  motion::Motion initial;  // the initial estimate at those frames
};

// at_rate: the source clip at the rate to write (its own skeleton), frame g at g / at_rate.fps.
// solve_source: the same clip at the solve's rate, which `initial` (m1) and `result` (m1 + d)
// were computed from (same frames and channel layout; target skeleton). When at_rate and
// solve_source have the same rate and frames, result and initial come back unchanged. Throws
// std::invalid_argument for motions of mismatched layouts or frame counts, or clips that are
// not the same length within one frame of the slower rate.
ResultAtRate result_at_rate(const motion::Motion& at_rate, const motion::Motion& solve_source,
                            const motion::Motion& initial, const motion::Motion& result,
                            const Target& target);

// The solve's constraints at another rate, so that what was held is checked at every frame
// written. Each constraint's samples are grouped into runs of consecutive instants (a sample's
// instant is the latest frame it reads); a run covers the time from its first sample's earliest
// frame to its last instant, and every frame of to_fps in that time gets a sample: its instant is
// that frame, and each earlier frame a sample reads keeps its distance in seconds (a non-skid
// pair one 30 Hz frame apart reads frames 4 apart at 120 Hz; at a coarser rate, at least one frame
// apart), kept inside the run. Per-sample
// params and locals are interpolated linearly in time between the run's samples. A run of one
// sample stays one sample, at the nearest frame, and so does a run of one-instant samples too
// brief to hold a frame of to_fps (its middle sample). Frames are clamped to 0 .. to_frames - 1. A
// constraint left with no sample is left out: a non-skid plant shorter than one frame of to_fps
// has no two frames written to compare. The same rate gives the set unchanged.
// Throws std::invalid_argument for rates that are not positive or to_frames < 1.
ConstraintSet constraints_at_rate(const ConstraintSet& set, double from_fps, double to_fps, int to_frames);

}  // namespace kg::retarget
