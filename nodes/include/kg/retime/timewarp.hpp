// The retiming p(t) of McCann et al. 2006 (fig. 2): output time t in [0, duration] to source time
// p in [0, source_duration], a uniform cubic B-spline, strictly increasing so playback never
// stops or runs backwards. The output frame at time t is the source pose at time p(t).
//
// Layout: S uniform segments of knot spacing h = duration / S; S + 3 controls, control j sitting
// at output time (j - 1) h (one before 0 and one after the end, unclamped so the ends are as
// smooth as the middle). p is strictly increasing when its controls are (ṗ is a positive
// combination of their differences).
//
// Constraints (all linear in the controls): p(0) = 0 and p(duration) = source_duration (the ends
// kept), and any number of pins p(t_i) = s_i (a source moment played at a given output time).
//
//   TimeWarp warp = TimeWarp::uniform(/*source*/ 4.0, /*duration*/ 2.0, /*segments*/ 20);
//   WarpSample s = warp.sample(0.5);           // p, ṗ, p̈ at t = 0.5 s (source seconds, per second, per s²)
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace kg::retime {

// p and its derivatives at one output time, and the controls that shape them there.
struct WarpSample {
  double p = 0;      // source seconds
  double pdot = 0;   // source seconds per output second
  double pddot = 0;  // per output second²
  int first = 0;     // controls first .. first + 3 carry the weights below
  std::array<double, 4> weight{}, weight_first{}, weight_second{};  // ∂p/∂c, ∂ṗ/∂c, ∂p̈/∂c
};

// A source moment played at a given output time.
struct Pin {
  double source_time = 0;  // seconds of the source clip
  double output_time = 0;  // seconds of the output
};

struct TimeWarp {
  double duration = 0;             // output seconds, > 0
  double source_duration = 0;      // source seconds, > 0
  std::vector<double> controls{};  // source seconds; segments() + 3 of them

  int segments() const { return static_cast<int>(controls.size()) - 3; }
  double knot_spacing() const { return duration / segments(); }
  // t is clamped to [0, duration].
  WarpSample sample(double t) const;
  double at(double t) const { return sample(t).p; }
  // The fastest playback within segment `segment` (0 .. segments() - 1, output times
  // [segment h, (segment + 1) h]): the largest ṗ there, source seconds per output second. Exact:
  // ṗ is a quadratic in output time on each segment.
  double max_pdot(int segment) const;
  // Whether every control exceeds the one before by more than `margin` source seconds.
  bool strictly_increasing(double margin = 0) const;

  // Playback at constant speed source_duration / duration, with `segments` segments (>= 1).
  static TimeWarp uniform(double source_duration, double duration, int segments);
};

// Playback held at one constant speed from a given moment: p(t) = source_start + speed (t −
// output_start) on every segment of the warp that meets [output_start, output_start + length]
// (output seconds). Whole segments: a cubic that is a line on part of a segment is that line on
// all of it. The retimer holds a flight this way (ballistic: ṗ constant, p̈ = 0).
struct Hold {
  double source_start = 0;  // source seconds
  double output_start = 0;  // output seconds
  double length = 0;        // output seconds, > 0
  double speed = 1;         // source seconds per output second, > 0
};

// The whole segments a hold covers, [first, last) (warp layout of `segments` over `duration`).
std::pair<int, int> held_segments(const Hold& hold, double duration, int segments);

// The linear constraints on a warp's controls: rows A c = b for the kept ends, the pins and the
// holds (one row per control a hold fixes: the line's value at the control's site).
struct WarpConstraints {
  Eigen::MatrixXd A;  // (2 + pins + held controls) x controls
  Eigen::VectorXd b;  // source seconds
};

// Throws std::invalid_argument naming the pin when a pin's times are not finite, it lies outside
// the open (0, duration) x (0, source_duration) (the ends are kept already), two pins share an
// output time, or pins run backwards (a later output time playing an earlier source moment: no
// increasing p(t) meets them); naming the hold when its numbers are not finite, its length or
// speed is not positive, it leaves [0, duration] x [0, source_duration], or two holds fix one
// control to different values (closer than three segments: use shorter segments).
WarpConstraints warp_constraints(double source_duration, double duration, int segments,
                                 const std::vector<Pin>& pins, const std::vector<Hold>& holds = {});

// A strictly increasing warp meeting the constraints (pins and holds): `playback` (samples of a playback to
// start from, in increasing output and source time, from (0, 0) to (duration, source_duration); empty:
// piecewise-constant speed between the ends and pins) fitted by a spline and corrected onto the
// constraints. Throws std::invalid_argument for a playback not increasing, or (naming the closest
// pair of pins) when `segments` is too coarse to pass the pins increasingly.
TimeWarp initial_warp(double source_duration, double duration, int segments, const std::vector<Pin>& pins,
                      const std::vector<Pin>& playback = {}, const std::vector<Hold>& holds = {});

// A warp of `segments` segments through the playback samples (output_times[i], source_times[i]),
// which start at (0, 0) and increase: its controls sample the piecewise-linear playback at their
// sites, so it follows the samples within the curvature a knot spacing rounds off and never runs
// backwards where they do not; duration and source duration are the last sample's, and p(0) = 0
// and p(duration) = source duration hold exactly. Throws std::invalid_argument for sizes that
// disagree, fewer than 2 samples, or samples that do not start at (0, 0) or do not increase.
// Callers needing strict increase check strictly_increasing() (samples that stop give a flat
// stretch).
TimeWarp fit_warp(const std::vector<double>& output_times, const std::vector<double>& source_times,
                  int segments);

}  // namespace kg::retime
