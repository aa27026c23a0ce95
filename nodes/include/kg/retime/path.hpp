// A clip as a path in its channels' space (McCann et al. 2006 §3.1): the channels' first and
// second derivatives with respect to source time, q' and q'', which with the retiming's ṗ and p̈
// give the retimed velocities q̇ = q' ṗ and accelerations q̈ = q'' ṗ² + q' p̈ (eq. 3 and 4).
//
//   PathDerivatives d = path_derivatives(motion);
//   Eigen::RowVectorXd qdot = d.first.row(f) * pdot;
#pragma once

#include "kg/motion/motion.hpp"

namespace kg::retime {

struct PathDerivatives {
  motion::FrameMatrix first;   // frames x channels: dq/dp, per second of source time
  motion::FrameMatrix second;  // frames x channels: d²q/dp², per second² of source time
};

// Central differences at interior frames, second-order one-sided ones at the two ends; rotation
// channels are differenced along their shorter way round, so a curve wrapping through +-180
// degrees has no spike. A clip of one frame has zero derivatives; two frames give a constant
// first derivative and a zero second.
//
// `smoothing` (seconds, >= 0) is the standard deviation of a Gaussian the channels are smoothed
// with before differencing. Capture noise of a millimetre becomes metres per second² at 120 Hz,
// which no contact force explains; a Gaussian keeps a parabola's second derivative exactly (a
// ballistic flight stays ballistic) and only shifts its value by a constant. Past each end the
// clip continues as the least-squares parabola through the frames within the kernel's reach (4
// standard deviations) of that end, so a parabola keeps its second derivative exactly to the
// last frame, and a clip shorter than the kernel (3 frames at 120 Hz under 0.04 s) is smoothed
// toward its own best parabola (two frames: their line) without reading past its ends. The
// derivatives only are smoothed: the clip itself is played unchanged.
//
// Throws std::invalid_argument when motion.check() fails or smoothing is negative or not finite.
PathDerivatives path_derivatives(const motion::Motion& motion, double smoothing = 0);

}  // namespace kg::retime
