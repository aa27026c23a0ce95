// The retimer of McCann et al. 2006 (§3.5, §3.6): the strictly increasing p(t) (timewarp.hpp)
// minimising ∫ objective(p(t), p̈(t), ṗ(t)²) dt over output time, with its ends kept, its total
// duration given and any pins and holds met exactly, by L-BFGS (Ceres' GradientProblemSolver) over the
// spline's controls with analytic gradients.
//
// The linear constraints are eliminated (controls = particular + null-space basis · y), so every
// iterate meets them to rounding; a step that would make the controls non-increasing is refused
// (the evaluation fails and the line search shortens it), and a weak log barrier on the control
// differences keeps playback from stopping. The integral is a trapezoid rule over output time on
// a SampleGrid: per segment of the spline, the fewest equal steps that each cover at most
// 1 / samples_per_frame of a source frame at that segment's fastest playback (§3.5: "samples at
// least once every quarter of a source frame"). The grid stays fixed during one L-BFGS solve, so
// the objective the line search sees does not jump as samples come and go; when the solution
// plays a segment faster than its steps allow, the grid is refined (every segment to a twentieth
// more steps than the solution needs, counts never shrinking) and the solve resumed, at most
// four solves in all.
//
//   RetimeResult r = retime(objective, {.duration = 2.0, .pins = {{.source_time = 1.2, .output_time =
//   0.5}}}); double source_time = r.warp.at(0.25);
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
  std::vector<Hold> holds{};  // stretches played at one constant speed, met exactly (warp_constraints)
  std::vector<Pin> start{};   // samples of a playback to start from (initial_warp's `playback`);
                              // empty: constant speed between the ends and pins
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
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// The grid of the trapezoid rule over a warp's output time [0, duration]: segment s of the warp
// (output times [s h, (s + 1) h], h its knot spacing) is cut into steps[s] equal steps, so its
// samples lie at s h + k h / steps[s], k = 0 .. steps[s]; neighbouring segments share the sample
// at their common knot. It depends on the warp's layout (duration and segment count), not on its
// controls: sample_grid() chooses the counts from a warp's playback.
//
//   SampleGrid grid = sample_grid(warp, 30, 4);            // warp: a TimeWarp of 30 fps source
//   double cost = integrate(objective, warp, grid);
//   for_each_sample(grid, warp.duration, [&](double t, double w) { total += w * f(t); });
struct SampleGrid {
  std::vector<int> steps{};  // per segment of the warp (TimeWarp::segments() entries), each >= 1

  int samples() const;  // sample points: Σ steps + 1 (the empty grid has none)
};

// The segments of the warp retime() solves for: duration / knot_spacing, rounded up, >= 1.
int warp_segments(const RetimeOptions& options);

struct RetimeResult {
  TimeWarp warp;
  bool converged = false;
  int iterations = 0;    // L-BFGS iterations over all grids
  int evaluations = 0;   // objective evaluations
  SampleGrid grid;       // the final grid (warp.segments() counts): sample_grid(warp) or finer
  int samples = 0;       // samples of the final grid: grid.samples()
  double objective = 0;  // the integral at the solution (barrier excluded)
  double seconds = 0;    // wall time of the solve
  std::string message;   // Ceres' termination message of the last solve, then each grid refinement
};

// Throws std::invalid_argument naming the option for options out of range (a duration that is
// not a finite positive number, a knot spacing giving more than kMaxSegments segments,
// max_iterations < 1, ...), or pins the warp cannot meet (warp_constraints, initial_warp).
RetimeResult retime(const PathObjective& objective, const RetimeOptions& options);

// The grid retime() starts from on its first warp (each refinement gives every segment at least
// the counts of this grid on the solution, plus a twentieth): per segment, the fewest steps (>= 1)
// such that no step covers more than 1 / samples_per_frame of a source frame at the segment's
// fastest playback (TimeWarp::max_pdot), i.e. ceil(h · max ṗ · source_fps · samples_per_frame),
// up to a relative 1e-9 so that a count met exactly is not doubled by rounding. source_fps:
// frames per source second (> 0); samples_per_frame: 1 .. kMaxSamplesPerFrame. Throws
// std::invalid_argument for either out of range, or a grid of more than kMaxGridSamples samples.
inline constexpr int kMaxGridSamples = 100'000'000;
SampleGrid sample_grid(const TimeWarp& warp, double source_fps, int samples_per_frame);

// Calls visit(t, weight) for every sample of `grid` in order of output time: t in output seconds
// over [0, duration], weight its trapezoid weight (output seconds; the weights sum to duration).
// `duration`: the warp's output seconds; the grid's segments are duration / steps.size() long.
template <class Visit>
void for_each_sample(const SampleGrid& grid, double duration, Visit&& visit) {
  const int segments = static_cast<int>(grid.steps.size());
  if (segments == 0) return;
  const double h = duration / segments;
  double carried = 0;  // the last segment's half step, owed to the knot they share
  for (int s = 0; s < segments; ++s) {
    const int n = grid.steps[static_cast<std::size_t>(s)];
    const double dt = h / n, start = s * h;
    visit(start, carried + dt / 2);
    for (int k = 1; k < n; ++k) visit(start + k * dt, dt);
    carried = dt / 2;
  }
  visit(duration, carried);
}

// The trapezoid rule on `grid` of `objective` along `warp` (output seconds times the objective's
// units), with its gradient with respect to the warp's controls written to `gradient` when not
// null (warp.controls.size() entries, caller-owned). Throws std::invalid_argument when the grid
// does not have warp.segments() counts, or a count is < 1.
double integrate(const PathObjective& objective, const TimeWarp& warp, const SampleGrid& grid,
                 double* gradient = nullptr);

}  // namespace kg::retime
