// Measures of a retargeted motion (issue 3 item 11), as free functions over plain data; the
// `retarget.metrics` node is a thin adapter writing them as JSON. What each measures and why:
//
//   constraint violation  per constraint kind, worst and mean (summarize_violations,
//                         constraint_kinds.hpp: an inequality row counts in the mean only when
//                         violated). Reported in cm for point kinds; parameter_range and
//                         orientation rows stay in their own unit (radians or metres; unit-vector
//                         components), since a cm figure would mean nothing for them.
//   foot skate            for each planted point: the points of `position` and `same_place`
//                         constraints over the frames their samples read, merged per point (the
//                         same joint and local offset, so the height and non-skid halves of one
//                         plant are one plant) and split into runs of consecutive frames, each
//                         frame sharing a constraint with the one before (two plants of one
//                         foot that touch at a coarse rate stay two). A run's
//                         skate is the greatest horizontal (world X/Z, +Y is up) distance of the
//                         point from where it was on the run's first frame (a sample's own point
//                         offsets, on a morphing segment, are used at its frame). Samples of
//                         `position` constraints whose own params move the target horizontally
//                         are not plants (a height that changes is: a morphing foot). A
//                         same_place tying two distant frames with nothing between gives two
//                         one-frame runs (skate 0): its miss shows in the violation figures.
//   RMS jerk              third finite difference of each channel times fps^3 (x[f+3] - 3x[f+2] +
//                         3x[f+1] - x[f]), RMS over frames and channels, position channels
//                         (m/s^3) apart from rotation channels (rad/s^3). Rotation channels are
//                         unwrapped first (2 pi jumps removed). For a sampled sine A sin(w t) the
//                         value is A (2 sin(w dt / 2) / dt)^3 / sqrt 2, which tends to A w^3 /
//                         sqrt 2 as dt -> 0.
//   jerk increase         result minus source (each on its own skeleton: same channel layout);
//                         also the RMS jerk of the displacement result - source itself, which
//                         does not let added and removed jerk cancel.
//   energy above cut-off  a cubic B-spline displacement with keys every k frames has k times fewer
//                         degrees of freedom than samples: like a signal sampled every k frames it
//                         carries frequencies up to the key grid's Nyquist frequency
//                         f_c = fps / (2 k) (its basis' response sinc^4(f k / fps) is down to
//                         (2/pi)^4 = 0.16 in amplitude there and keeps only weak images above).
//                         Energy added above f_c is what no displacement of that spacing could
//                         have added: the per-frame IK's snaps. Measured on the displacement d =
//                         result - reference (the initial estimate when given, else the source;
//                         rotations unwrapped over time from within pi of 0) with the
//                         orthonormal DCT-II of each channel (the DFT of its even extension,
//                         so no spurious edge discontinuity leaks into high frequencies): bin m
//                         is m fps / (2 N) Hz; the figure is sum over bins above f_c of X_m^2 as a
//                         fraction of sum d^2 (Parseval), position and rotation channels apart.
//   solve time            not measurable here: passed through from the solver when wired (the
//                         node's optional `solve_seconds` input, e.g. retarget.per_frame_ik's
//                         `seconds` output), null in the JSON otherwise, and in reproducible
//                         runs (graph::RunContext::reproducible), where it is a figure only.
//
//   RetargetMetrics m = compute_metrics({.result = &out, .constraints = &set, .kinds = &table,
//                                        .source = &clip, .initial = &m1, .frames_per_key = keys});
//   write_metrics_json(std::cout, m);
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/base/report.hpp"
#include "kg/motion/motion.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

// ---- foot skate ----
struct PlantSkate {
  std::string label;  // of the first constraint naming the point at the run's first frame
  PointRef point;
  int first_frame = 0;  // the run of consecutive frames
  int last_frame = 0;
  std::vector<Eigen::Vector3d> locals;  // the point's offset at each frame of the run (morphing)
  double travel = 0;    // metres, greatest horizontal distance from the first frame's position
  int worst_frame = 0;  // where it is reached
};
struct SkateSummary {
  std::vector<PlantSkate> plants;  // by point (constraint order), then frame
  double worst = 0;                // metres, 0 without plants
  double mean = 0;                 // over plants
};
// Plants of character 0 in `set` (travel left 0), see the header comment; constraints reading a
// point of another character are not plants of it and are passed over.
std::vector<PlantSkate> find_plants(const ConstraintSet& set);
// Plants and their travel in `motion` (character 0); throws std::out_of_range for frames or
// joints outside it.
SkateSummary foot_skate(const ConstraintSet& set, const PoseCache& poses);

// ---- jerk ----
struct JerkFigures {
  double translation = 0;  // RMS, m/s^3, over position channels (0 when there are none)
  double rotation = 0;     // RMS, rad/s^3, over rotation channels
  int translation_channels = 0;
  int rotation_channels = 0;
  int samples = 0;  // third differences per channel: frames - 3 (0 below 4 frames)
};
JerkFigures rms_jerk(const motion::Motion& motion);
// RMS over every joint origin's world position of the third difference times fps^3 (m/s^3; 0
// below 4 frames): unlike the channels' jerk it compares motions of different structures (a
// capture and a robot).
double rms_joint_jerk(const motion::Motion& motion);
// Jerk of the displacement result - reference (same frame count and channel layout, else
// std::invalid_argument).
JerkFigures rms_jerk_of_displacement(const motion::Motion& result, const motion::Motion& reference);

// ---- energy above the key-spacing cut-off ----
// fps / (2 frames_per_key), Hz (header comment).
double key_cutoff_hz(double fps, int frames_per_key);
struct BandEnergy {
  double total = 0;     // sum of d^2 (m^2 or rad^2)
  double above = 0;     // of it, above the cut-off
  double fraction = 0;  // above / total (0 when total is 0)
  int channels = 0;
};
// One signal sampled at `fps`: its energy and the part above `cutoff_hz` (orthonormal DCT-II).
BandEnergy energy_above(const Eigen::Ref<const Eigen::VectorXd>& signal, double fps, double cutoff_hz);
struct AddedEnergy {
  BandEnergy translation, rotation;
  double min_cutoff_hz = 0, max_cutoff_hz = 0;  // over the channels
};
// d = result - reference per channel (rotations unwrapped); frames_per_key: one entry per
// channel (or one for all), each >= 1, counted in frames at keys_fps (0: result's rate; a solve at
// 30 Hz written at 120 Hz keeps its cut-off in Hz). Throws std::invalid_argument for mismatched
// motions or keys.
AddedEnergy energy_above_cutoff(const motion::Motion& result, const motion::Motion& reference,
                                const std::vector<int>& frames_per_key, double keys_fps = 0);

// ---- everything, and its JSON ----
struct MetricsInputs {
  const motion::Motion* result = nullptr;      // required (character 0)
  const motion::Motion* result2 = nullptr;     // character 1, required when a constraint names it
  const Target* target = nullptr;              // optional: a morphing target gives each frame its skeleton
  const ConstraintSet* constraints = nullptr;  // required
  const ConstraintKindTable* kinds = nullptr;  // required: every kind the set names
  const motion::Motion* source = nullptr;      // optional: before adaptation, own skeleton
  const motion::Motion* initial = nullptr;     // optional: the initial estimate m1
  std::vector<int> frames_per_key{};           // per channel, or one for all; empty: 4
  double keys_fps = 0;                         // the rate frames_per_key counts at; 0: result's
  std::optional<double> solve_seconds{};
  double tolerance = 1e-3;  // metres (or channel unit): violated_rows
};
struct KindMetrics {
  KindViolation violation;  // metres (or the native unit)
  bool in_metres = true;    // false for parameter_range, orientation and kinds without points
};
struct RetargetMetrics {
  std::string motion_name;
  int frames = 0;
  double fps = 0;
  std::vector<KindMetrics> kinds;     // sorted by kind name
  double worst_violation_metres = 0;  // over the kinds in metres
  SkateSummary skate;
  // The initial estimate's travel over the same plants (with an initial estimate): what copying
  // the scaled source onto the target gives, at the same rate, for comparison; a capture's own
  // jitter between the solve's frames shows in both when the result is written at a finer rate.
  std::optional<SkateSummary> initial_skate;
  JerkFigures jerk;
  std::optional<JerkFigures> source_jerk, displacement_jerk;  // with a source
  std::optional<AddedEnergy> energy;                          // with an initial estimate or source
  std::string energy_reference;                               // "initial", "source" or ""
  std::optional<double> solve_seconds;
};
// Violations cover every constraint (across characters too, with result2); foot skate, jerk and
// energy are character 0's. Throws std::invalid_argument for missing inputs, constraints naming
// character 1 without result2, or mismatched motions (message says which).
RetargetMetrics compute_metrics(const MetricsInputs& inputs);
// The JSON document (version 1), lengths in cm as the header comment says.
Report metrics_report(const RetargetMetrics& metrics);
// metrics_report's text and a blank line, as io.write_report writes it.
void write_metrics_json(std::ostream& os, const RetargetMetrics& metrics);

}  // namespace kg::retarget
