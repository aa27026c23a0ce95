// Time-optimal retiming within the hulls (Bobrow et al. 1985; the two passes of TOPP-RA, Pham &
// Pham 2018): the fastest playback of the path whose retiming state (p̈, ṗ²) stays inside every
// frame's hull. With b = ṗ² and a = p̈ at source frame i (source time i / fps) and the path
// discretised as b[i+1] = b[i] + 2 a[i] / fps, a backward pass finds each frame's controllable
// speeds (the b from which some admissible a reaches the next frame's controllable set) and a
// forward pass plays every frame as fast as it may: the largest controllable start and, at each
// frame, the largest admissible acceleration.
//
// A hull of a single point (a frame whose polytope is empty: flight, or mocap that is not
// exactly physical) admits a small box around it: ṗ² within `point_tolerance` of the point's
// (relative), p̈ within the change of ṗ² that allows over one frame.
//
//   TimeOptimalResult r = time_optimal(polygons, 30.0, {});
//   if (r.feasible) std::cout << "shortest duration " << r.duration << " s\n";
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/retime/timewarp.hpp"

namespace kg::retime {

// A convex polygon in the (p̈, ṗ²) plane, vertices counter-clockwise (1 vertex: a point; 2: a
// segment).
using Polygon = std::vector<Eigen::Vector2d>;

struct TimeOptimalOptions {
  double point_tolerance = 0.05;  // relative half-width in ṗ² of the box around a point hull
  double knot_spacing = 0.1;      // output seconds between the fitted warp's controls (> 0); a
                                  // playback needing more than kMaxSegments of them is refused
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

struct TimeOptimalResult {
  bool feasible = false;
  std::string message;               // why not, naming the frame; or a summary
  int blocking_frame = -1;           // the first frame with no controllable speed, -1 when feasible
  std::vector<double> pdot_squared;  // per source frame, the time-optimal ṗ²
  std::vector<double> output_times;  // per source frame, when it plays (output seconds)
  double duration = 0;               // output seconds: the shortest feasible duration
  TimeWarp warp;                     // the profile fitted by a spline (fit_warp); a fit that does
                                     // not increase strictly makes the result infeasible
};

// One polygon per source frame (>= 2 frames), fps > 0. Throws std::invalid_argument for an empty
// polygon or bad sizes; an infeasible path is a result (feasible = false), not an exception.
TimeOptimalResult time_optimal(const std::vector<Polygon>& hulls, double fps,
                               const TimeOptimalOptions& options);

}  // namespace kg::retime
