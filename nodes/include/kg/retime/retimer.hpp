// The retimer of McCann et al. 2006 (§3.5, §3.6): the strictly increasing p(t) (timewarp.hpp)
// minimising ∫ objective(p(t), p̈(t), ṗ(t)²) dt over output time, with its ends kept, its total
// duration given and any pins met exactly, by L-BFGS (Ceres' GradientProblemSolver) over the
// spline's controls with analytic gradients.
//
// The linear constraints are eliminated (controls = particular + null-space basis · y), so every
// iterate meets them to rounding; a step that would make the controls non-increasing is refused
// (the evaluation fails and the line search shortens it), and a weak log barrier on the control
// differences keeps playback from stopping. The integral is a trapezoid rule over output time
// with at least `samples_per_frame` samples per source frame (§3.5: a quarter frame); when the
// solution plays faster than the grid allows, the grid is refined and the solve resumed.
//
//   RetimeResult r = retime(objective, {.duration = 2.0, .pins = {{.source_time = 1.2, .output_time = 0.5}}});
//   double source_time = r.warp.at(0.25);
#pragma once

#include <string>
#include <vector>

#include "kg/retime/timewarp.hpp"

namespace kg::retime {

// The integrand at one sample and its partial derivatives.
struct SampleCost {
  double value = 0;
  double d_p = 0;      // per source second
  double d_pddot = 0;  // with respect to p̈
  double d_pdot2 = 0;  // with respect to ṗ²
};

// What the retimer minimises: eq. 14's integrand at source time p (seconds) and retiming state
// (p̈, ṗ²). `hint` is the caller's cursor for query locality (start it at 0 and pass it back on
// the next call); implementations may ignore it.
class PathObjective {
 public:
  virtual ~PathObjective() = default;
  virtual SampleCost evaluate(double p, double pddot, double pdot_squared, int& hint) const = 0;
  virtual double source_duration() const = 0;  // seconds
  virtual double source_fps() const = 0;       // frames per second of the source
};

// The solve holds two dense square matrices of the controls' count (the constraints' null-space
// basis): at most this many segments (2 x 134 MB), i.e. knot_spacing >= duration / kMaxSegments.
inline constexpr int kMaxSegments = 4096;
inline constexpr int kMaxSamplesPerFrame = 1000;

struct RetimeOptions {
  double duration = 0;        // output seconds (finite, > 0)
  std::vector<Pin> pins{};    // source moments at output times (finite; warp_constraints)
  double knot_spacing = 0.1;  // output seconds between the spline's controls (> 0, at most
                              // kMaxSegments segments over the duration)
  int samples_per_frame = 4;  // at least this many samples per source frame (1 .. kMaxSamplesPerFrame)
  int max_iterations = 500;   // L-BFGS iterations per grid (>= 1)
  // Both tolerances are relative (finite, >= 0). A solve ends when an iteration changes the
  // objective by less than function_tolerance times its value (Ceres' own test), or when the
  // gradient's max-norm falls to gradient_tolerance times its max-norm at the start. Ceres tests
  // the gradient absolutely (max-norm <= its gradient_tolerance); retime() passes it this option
  // times the starting max-norm, because the objective's units (α, β, the clip's torques and
  // duration) vary by orders of magnitude and an absolute threshold would stop a small objective
  // before it moved and never stop a large one.
  double function_tolerance = 1e-10;
  double gradient_tolerance = 1e-10;
};

struct RetimeResult {
  TimeWarp warp;
  bool converged = false;
  int iterations = 0;      // L-BFGS iterations over all grids
  int evaluations = 0;     // objective evaluations
  int samples = 0;         // samples of the final grid
  double objective = 0;    // the integral at the solution (barrier excluded)
  double seconds = 0;      // wall time of the solve
  std::string message;     // Ceres' termination message, and any grid refinement
};

// Throws std::invalid_argument naming the option for options out of range (a duration that is
// not a finite positive number, a knot spacing giving more than kMaxSegments segments,
// max_iterations < 1, ...), or pins the warp cannot meet (warp_constraints, initial_warp).
RetimeResult retime(const PathObjective& objective, const RetimeOptions& options);

// The integral of `objective` along `warp` on the grid retime() would use, with its gradient with
// respect to the warp's controls when `gradient` is not null (controls.size() entries).
double integrate(const PathObjective& objective, const TimeWarp& warp, int samples, double* gradient = nullptr);

// Samples of the grid giving at least `samples_per_frame` samples per source frame along `warp`.
int grid_samples(const TimeWarp& warp, double source_fps, int samples_per_frame);

}  // namespace kg::retime
