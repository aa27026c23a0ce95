// Filters over sampled curves, shared by both papers and the plugins: angle unwrapping and
// Gaussian smoothing. Plain data; one curve is a span or an Eigen column, sampled per frame.
//
//   std::vector<int> turns = unwrap_angles(curve);              // radians, in place
//   Eigen::MatrixXd smooth = gaussian_smoothed(curves, 2.0, CurveEnds::Parabola);  // per column
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

namespace kg::motion {

// Whole turns per sample that make `angles` (radians) continuous: angles[f] + 2 pi turns[f] moves
// by at most pi from one sample to the next (a step of exactly pi is not a wrap); turns[0] = 0.
// Adding whole turns leaves every sample that needs none bit for bit as it was.
std::vector<int> unwrap_turns(std::span<const double> angles);

// `angles` unwrapped in place (angles[f] += 2 pi turns[f]); returns the turns added, so that a
// caller can put the curve back on its original branch.
std::vector<int> unwrap_angles(std::span<double> angles);

// The curve `x` (at least one sample) extended past both ends by odd reflection about its end
// samples, x[-k] = 2 x[0] - x[k] (scipy.signal.filtfilt's padding), repeated as often as `i`
// needs: a straight line continues as itself. Any index.
double odd_extended(std::span<const double> x, long i);

// How a smoothing kernel reads past the ends of a curve.
enum class CurveEnds {
  // Odd reflection (odd_extended): lines stay straight to the last sample, which is kept as it is.
  OddReflection,
  // The least-squares parabola through the samples within the kernel's reach of that end (the
  // whole curve when it is shorter; the line through two samples): a ballistic flight keeps its
  // second derivative exactly to the last frame, where an odd reflection would bend it straight.
  Parabola,
};

// Each column of `curves` (samples x curves) convolved with a normalised Gaussian of
// `sigma_frames` samples (> 0 and at most 2^20), truncated at 4 sigma: zero phase. Curves of
// fewer than 2 samples come back as they are. Throws std::invalid_argument for another sigma.
Eigen::MatrixXd gaussian_smoothed(const Eigen::MatrixXd& curves, double sigma_frames, CurveEnds ends);

// The q-quantile of v (q in [0, 1], clamped) by rank: the element at floor(q (n - 1)) of v
// sorted; 0 for an empty v.
double percentile(std::vector<double> v, double q);

}  // namespace kg::motion
