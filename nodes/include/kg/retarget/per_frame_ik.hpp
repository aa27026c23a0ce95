// The per-frame inverse kinematics baseline of Gleicher 1998 §3.1: the same constraints as the
// spacetime solver, met frame by frame, each frame solved on its own. It is the comparison the
// paper's Figure 3 makes: a frame does not know a constraint starts on the next one, so the
// point snaps to its target the frame the constraint switches on, and inside a plant each frame
// picks its own mix of joint changes. Those snaps are the "jerkiness" the metrics measure.
//
// It is meant as a fair baseline, not a strawman: each frame is solved to convergence by
// Levenberg-Marquardt on the damped least-squares objective the spacetime solver uses (eq. 4),
// written over the frame's channels q instead of B-spline controls,
//     F_f(q) = 1/2 sum_rows (w_r rho_r(q))^2 + 1/2 eps (q - q0)^T M (q - q0),
// q0 = the initial motion's frame f (the minimum-change damping: the displacement from the
// initial estimate), M = channel_sensitivity (spacetime.hpp: the same per-channel weights, so a
// rotation's change is measured by how far it moves the figure's points), rho_r = r for an
// equality row and min(r, 0) for an inequality row (active set: a violated inequality row acts as
// an equality, a satisfied one drops out; re-evaluated at every iterate). Jacobians are analytic:
// d row / d q = (d row / d world points, from the kind) x point_jacobian (kinematics.hpp), plus
// d row / d values for channel constraints. Steps solve (J^T J + eps M + lambda D) dq = -grad F
// with D = diag(J^T J + eps M), lambda adapted (shrunk on an accepted step, grown on a refused one),
// over the channels the frame's rows can move (the chains above its points, its value channels):
// the others have zero Jacobian columns and stay at q0 exactly, so leaving them out is exact.
// A frame stops when its rows are met (options.tolerance) and the step is below 1e-7 m (M-weighted),
// or when no step lowers F (then, if rows are still violated, the frame counts as unmet).
// Soft constraints (Constraint::soft) weigh in F but are never waited for: a frame's "met" and
// the result's worst_violation and frames_unmet look at required rows only, so a frame with soft
// rows alone stops when its step is below 1e-7 m or no step lowers F.
//
// Which rows a frame sees: a sample belongs to the latest frame it reads. Its points and values
// at that frame are unknowns; those it reads at earlier frames are fixed at their already-solved
// positions (frames are solved in order, forward in time). So a non-skid same_place sample
// [fa, fb] pulls the point at fb to where the solved frame fa left it: the plant is held from its
// first frame on, as a sequential IK would do it. Frames no sample belongs to keep q0.
//
// One character only (every PointRef/ChannelRef must name character 0).
//
//   PerFrameIkResult r = solve_per_frame_ik(initial, set, [&](const std::string& n) { return table.find(n);
//   }); if (r.frames_unmet > 0) std::cerr << r.message << '\n';
#pragma once

#include <string>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/spacetime.hpp"

namespace kg::retarget {

struct PerFrameIkOptions {
  double epsilon = 1e-4;    // damping weight of (q - q0)^T M (q - q0), as SpacetimeOptions::epsilon
  int max_iterations = 50;  // Levenberg-Marquardt iterations per frame
  double tolerance = 1e-4;  // a frame's rows are met when every |r| (equality) and max(0, -r)
                            // (inequality) is at most this: metres, or radians for channel rows
  // Each frame starts from the previous frame's solution moved as the initial motion moves
  // between the two (q*_{f-1} + q0_f - q0_{f-1}) instead of from q0_f; the damping still pulls
  // toward q0_f. For a target far from its initial pose (a robot started at its rest pose), where
  // a cold start can land each frame in another local minimum (a flipped hip).
  bool warm_start = false;
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

struct PerFrameIkResult {
  motion::Motion motion;  // the initial motion with every constrained frame solved
  double seconds = 0;     // wall time of the solve
  int iterations = 0;     // over all frames
  int max_frame_iterations = 0;
  int frames_constrained = 0;  // frames some sample belongs to
  int frames_unmet = 0;        // of those, frames whose rows stayed violated past tolerance
  double worst_violation = 0;  // max over all rows of the result (metres or radians)
  int worst_frame = -1;        // the frame holding it (-1 when none)
  std::string message;         // "met all constraints on 52 frames ..." or "... unmet on frames ..."
};

// Throws std::invalid_argument (with the label) for an unknown kind, a constraint its kind
// refuses, a reference to a second character, or a frame, joint or channel out of range; an
// unreachable constraint is not an error: it is counted in frames_unmet.
PerFrameIkResult solve_per_frame_ik(const motion::Motion& initial, const ConstraintSet& set,
                                    const KindFinder& kinds, const PerFrameIkOptions& options = {});

}  // namespace kg::retarget
