// Retiming a clip from its hulls, end to end (McCann et al. 2006 §3.5-§4): the target torques τ'
// (keep the look, least effort, or another clip's), the baked objective, the solve (retimer.hpp)
// or the time-optimal playback (time_optimal.hpp), and what came of it: the objective's parts, the
// share of output frames whose timing lies inside their hulls, and, when the requested duration
// leaves frames outside, the shortest feasible duration, so an impossible request is reported
// rather than hidden.
//
//   ClipRetime r = retime_clip(hulls, torques.frames, fps, {.solve = {.duration = 1.2}});
//   std::cout << r.message;   // converged? inside? shortest feasible duration?
#pragma once

#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/retime/hulls.hpp"
#include "kg/retime/objective.hpp"
#include "kg/retime/path_torques.hpp"
#include "kg/retime/retimer.hpp"
#include "kg/retime/time_optimal.hpp"

namespace kg::retime {

enum class TorqueTarget {
  Original,   // τ' = the clip's own torques at its original timing: keep the look
  Zero,       // τ' = 0: least effort
  Reference,  // τ' = another clip's torques at its original timing (same skeleton), by normalised time
};
const char* to_string(TorqueTarget target);  // "match", "minimal", "reference"

enum class RetimeMode {
  Optimise,     // minimise eq. 14 for the requested duration and pins
  TimeOptimal,  // the shortest duration within the hulls (duration and pins ignored)
};

enum class FlightTiming {
  Free,  // flight frames weigh in the objective like the others (times flight_weight)
  // Every flight (two or more consecutive flight frames) is played at one constant speed, exactly
  // (TimeWarp holds): ṗ = √(|g| / motion::kEarthGravity), p̈ = 0, the only ballistic timing under the
  // hulls' gravity g (straight down; another direction: no constant speed is ballistic, and the
  // flights stay free, said in the message). A free solve first finds where each flight plays;
  // the held solve keeps its middle there and the ground phases take the rest of the duration.
  Hold,
};
const char* to_string(FlightTiming timing);  // "free", "hold"

struct ClipRetimeOptions {
  RetimeOptions solve{};  // duration (output s), pins, knot spacing, grid, iterations
  RetimeMode mode = RetimeMode::Optimise;
  TorqueTarget target = TorqueTarget::Original;
  double alpha = 1000;                        // feasibility weight (ObjectiveWeights)
  double beta = 1;                            // torque weight
  double flight_weight = 1;                   // multiplies alpha on flight frames (ObjectiveWeights::flight)
  FlightTiming flights = FlightTiming::Free;  // Optimise mode only
  double inside_tolerance = 0.01;             // plane units: a timing this close to its hull counts as inside
  TimeOptimalOptions time_optimal{};
  // Throws std::invalid_argument naming the field, its value and its range (DESIGN.md 15):
  // alpha, beta, flight_weight and inside_tolerance >= 0 and finite, time_optimal.validate(),
  // and in Optimise mode solve.validate() (the time-optimal mode takes its duration from the
  // hulls and of `solve` only samples_per_frame, checked alone).
  void validate() const;
};

struct ClipRetime {
  TimeWarp warp;
  RetimeResult solve;                         // Optimise mode
  std::optional<TimeOptimalResult> shortest;  // TimeOptimal mode, or computed when frames are outside
  double feasibility = 0;                     // ∫ α |q − c|² dt at the result
  double torque = 0;                          // ∫ β |τ − τ'|² / τ_scale² dt
  double torque_scale = 1;                    // N m
  // Output frames (at the source's rate over the output duration) whose (p̈, ṗ²) lies within
  // inside_tolerance of the hull of the source frame they play, over all output frames; and of
  // those playing frames with an empty polytope, the share at their closest point: for flight, a
  // root residual within a tenth of the body's weight of its least; otherwise within
  // inside_tolerance of the point.
  double share_inside = 0;
  double share_at_point = 1;
  // The output frames at the source's rate the shares count (the clip written at another rate
  // has output_frame_count(warp, fps) frames, playback.hpp).
  int output_frames = 0;
  // Every output frame playing a frame with a feasible polytope lies inside its hull. Frames
  // without one (flight, not exactly physical) are reported by share_at_point, not counted here:
  // captured flights scatter about their least-squares points.
  bool feasible = true;
  int flights = 0;       // FlightTiming::Hold: the flights found (runs of frames without contact)
  int flights_held = 0;  // FlightTiming::Hold: the flights played at held_speed
  // FlightTiming::Hold with flights not held: the shortest output duration (s) at which the warp's
  // spline holds every flight (found by bisection between the request and the source's duration
  // at held_speed, to 1 ms); empty when every flight is held, or pins fix output times.
  std::optional<double> duration_holding_flights;
  double held_speed = 0;    // source seconds per output second
  std::string flight_note;  // FlightTiming::Hold: what was held, or why nothing was
  std::string message;      // one paragraph for logs: first, in one sentence, what could not be met
};

// Throws std::invalid_argument for inputs that disagree (sizes, a Reference target without
// `reference` torques) and what retime() throws (contradictory pins, ...).
ClipRetime retime_clip(const Hulls& hulls, std::span<const FrameTorques> torques, double fps,
                       const ClipRetimeOptions& options, const motion::Skeleton& skeleton,
                       std::span<const Eigen::VectorXd> reference = {});

// Per source frame, as JSON: status, hull vertices and centre, the timing (p̈, ṗ²) the warp plays
// it at, whether that lies inside, the contact forces per patch there (force N, centre of pressure
// m) and the generalised forces τ (N, N m). `patch_names` name the patches (Hulls::patch_names).
void write_forces_json(std::ostream& os, const Hulls& hulls, std::span<const FrameTorques> torques,
                       const TimeWarp& warp, double fps);

}  // namespace kg::retime
