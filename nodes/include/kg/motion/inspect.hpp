// The motion doctor (`kinegraph inspect`, node motion.inspect): what a clip is and what is wrong
// with it, each finding with its evidence, and the --set values that fix what can be fixed.
//
//   MotionInspection i = inspect_motion(clip, {});   // clip: imported with every frame (trim none)
//   for (const std::string& line : i.summary) std::cout << line << '\n';
//   JsonWriter w(std::cout); write_inspection_json(w, i);
//
// Units: metres, seconds, m/s², world +Y up (skeleton.hpp). Frame numbers are the clip's, from
// 0, calibration frames included: the analyses after the calibration check (plants, flights,
// floor, pops) run on the frames after them and report the clip's numbers all the same. The
// flights that tell the rate are found from heights alone (the same at any rate); the plants,
// the flights reported and the pops are then found at the rate believed.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "kg/base/json.hpp"
#include "kg/motion/calibration.hpp"
#include "kg/motion/footplants.hpp"
#include "kg/motion/motion.hpp"

namespace kg::motion {

// Candidates for a header's wrong rate: the true rate is the header's times one of these.
inline constexpr double kRateFactors[] = {0.125, 0.25, 1.0 / 3, 0.5, 1, 2, 3, 4, 8};
// A flight's gravity, and so the rate implied, is taken as a rate factor when the factor the
// flights imply is within this of it (relative): the pelvis is not the centre of mass exactly, so
// the jumps of ../shared/data show 8.8 to 10.1 m/s² at their right rate.
inline constexpr double kRateTolerance = 0.15;
// Only flights whose pelvis rises this far (m) weigh the rate: a few-frame gap between a run's
// steps, or a dancer's centimetre hop, fits a parabola of any curvature. The rise, g T² / 8, is the
// same at any frame rate.
inline constexpr double kMinFlightRise = 0.05;
// And only flights that are a parabola: the fit's RMS residual within this share of the rise (the
// jumps of ../shared/data: 0.5 to 1.4%; a partner's dip in the salsa clip 60_10: 20%).
inline constexpr double kMaxFlightResidual = 0.05;

struct InspectOptions {
  FootplantOptions plants{};
  // A frame pops when a joint's acceleration there exceeds pop_ratio times that joint's 95th
  // percentile over the clip and pop_floor m/s² (capture noise at 120 Hz alone gives tens).
  double pop_ratio = 5;
  double pop_floor = 50;
  int min_flight_frames = 5;  // frames a flight needs for its gravity (a parabola fit)
  void validate() const;
};

struct JointSummary {
  std::string name;
  int parent = -1;
  std::vector<std::string> channels{};  // "Xposition", "Zrotation", ...
  double rest_length = 0;               // m: the offset from the parent (0 for a root)
};

struct PointPlants {
  std::string point;
  std::vector<std::pair<int, int>> spans{};  // first, last frame of each plant
  double worst_skate = 0;                    // m: the largest slide during a plant
};

struct FlightSpan {
  int first = 0, last = 0;        // frames with every foot point off the floor, none planted
  double seconds = 0;             // at the rate believed (source_fps)
  std::optional<double> gravity;  // m/s² at the rate believed: a parabola through the pelvis's
                                  // heights (min_flight_frames or more)
  double rise = 0;                // m: the parabola's apex above its ends' level
  bool weighs_rate = false;       // rise >= kMinFlightRise, fitted within kMaxFlightResidual of it
};

struct Pop {
  int frame = 0;
  std::string joint;
  double acceleration = 0;  // m/s² at the rate believed
};

struct MotionInspection {
  std::string clip;
  std::vector<JointSummary> joints;
  int frames = 0;
  double header_fps = 0;  // the clip's rate as read (its file's, or the importer's default)
  double source_fps = 0;  // the rate believed: header_fps, or what its flights' gravity implies
  std::string rate_evidence;
  std::string pelvis;      // the joint whose flight heights are fitted
  std::string up;          // "y", "z" or "custom": the file axis taken as up
  double unit_metres = 1;  // the file's length unit, in metres
  CalibrationCut calibration;
  std::vector<int> calibration_frames;  // 0 .. calibration.frames - 1
  double floor = 0;                     // m
  std::vector<PointPlants> plants;
  std::vector<std::string> plant_notes;  // which points, floor; and points that touch with no plant
  std::vector<FlightSpan> flights;
  double penetration = 0;  // m: the deepest a foot point goes below the floor (0: never)
  int penetration_frame = -1;
  std::string penetration_point;
  std::vector<Pop> pops;
  std::vector<std::string> fixes;    // "--set source_fps=120", "--set trim=1.."
  std::vector<std::string> summary;  // the findings, one line each, for people
};

// Throws std::invalid_argument for a clip of fewer than 3 frames, no foot points found (the
// message of detect_footplants) or options out of range.
MotionInspection inspect_motion(const Motion& motion, const InspectOptions& options = {});

// The rate a clip's free-fall flights imply, and the evidence: inspect_motion's source_fps and
// rate_evidence (the header's rate when no flight weighs it). What `source_fps: auto` applies.
struct RateCheck {
  double fps = 0;
  std::string evidence;
};
RateCheck rate_from_flights(const Motion& motion, const InspectOptions& options = {});

// The inspection as one JSON object: clip, joints, frames, header_fps, source_fps, duration_s,
// up, units (`units`: the caller's name of unit_metres, e.g. io::unit_name), calibration_frames,
// plants, flights (each with its gravity), floor_m, penetration, pops, fixes, summary.
void write_inspection_json(JsonWriter& w, const MotionInspection& inspection, const std::string& units);

}  // namespace kg::motion
