// Uniform cubic B-spline bases, shared by the retargeting's displacement maps (Gleicher 1998
// §3.7, kg/retarget/displacement.hpp) and the retiming's time warp (McCann 2006 §4).
//
// Knot layout (spacing k frames, a clip of F frames): S = max(1, ceil((F - 1) / k)) uniform
// segments, segment i covering frames [i k, (i + 1) k]; S + 3 control points, control j sitting
// at frame (j - 1) k (one control before frame 0, up to two past the last frame). Frame f lies in
// segment i = min(floor(f / k), S - 1) at s = f / k - i in [0, 1], and only controls i .. i + 3
// are non-zero there, with the weights
//   (1 - s)^3 / 6, (3 s^3 - 6 s^2 + 4) / 6, (-3 s^3 + 3 s^2 + 3 s + 1) / 6, s^3 / 6.
//
//   BasisAt b = bspline_basis(12, 120, 4);   // controls b.first .. b.first + 3 at frame 12
#pragma once

#include <array>

namespace kg::motion {

// Basis of one frame of one spline: weights of controls first .. first + 3 (they sum to 1).
struct BasisAt {
  int first = 0;
  std::array<double, 4> weight{};
};

// The four weights of a uniform cubic B-spline segment at s in [0, 1] (those above) and their
// first and second derivatives with respect to s (divide by the knot spacing, and its square,
// for derivatives with respect to time).
struct CubicWeights {
  std::array<double, 4> value{}, first{}, second{};
};
CubicWeights cubic_bspline_weights(double s);

// Segments and controls of a spline of `spacing` frames over `frames` frames (both >= 1;
// std::invalid_argument otherwise).
int bspline_segment_count(int frames, int spacing);
int bspline_control_count(int frames, int spacing);
// Basis at frame `frame` (0 <= frame < frames; std::out_of_range otherwise).
BasisAt bspline_basis(int frame, int frames, int spacing);
// Basis at a fractional frame position (for continuity tests and resampling), same range.
BasisAt bspline_basis_at(double frame, int frames, int spacing);

}  // namespace kg::motion
