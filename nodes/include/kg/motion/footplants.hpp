// Footplant detection (Gleicher 1998 §3.5, §7.1), shared by both papers (the retargeting's plant
// constraints, the retiming's contacts): spans of frames during which a point of a foot
// (heel/ankle, toe) rests on the floor, found from its height and horizontal speed with
// hysteresis.
//
// Detection, per point: height above the floor h(f) and horizontal speed v(f) (central
// differences over +-k frames, k = max(1, round(fps / 60)), metres per second). A plant starts
// where h <= height_threshold and v <= the point's speed threshold (speed_threshold, or
// speed_relative times its 90th-percentile speed, or body_relative times the body's horizontal
// speed at that frame, whichever is most), and lasts while h <= height_threshold *
// hysteresis and v <= that threshold * hysteresis; the span's end frames farther than
// trim_distance from its median position are trimmed off (the roll into and out of a plant;
// where the body runs, only beyond body_relative x its pace x min_duration_s), spans shorter than
// the minimum duration are dropped, and two spans of a point parted by a lift shorter than
// bridge_s that comes back within bridge_distance are one. Each point's height is measured above its own rest
// level (an ankle rests 7-10 cm above a toe tip): its lowest height within `rest_window_s` around the frame
// (captured floors slope and drift by centimetres between steps), or with rest_window_s = 0 the
// `floor_percentile` of its heights over the clip. The floor (for the constraints: above-floor regions) is
// given, or estimated as the `floor_percentile` of the lowest point's heights.
//
//   FootplantDetection d = detect_footplants(walk, {});
//   for (const Footplant& p : d.plants) use(d.points[p.point].name, p.first_frame, p.last_frame);
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::motion {

struct FootplantOptions {
  // Points by joint name: "LeftToeBase" (the joint's origin), "LeftToeBase/end" (its first End
  // Site) or "LeftFoot[0 -0.07 -0.05]" (a point in the joint's frame, metres: a heel). Empty: per foot, the
  // ankle (foot joint origin) and the toe tip (End Site of the toe joint, else the toe joint, else the foot's
  // End Site), by common names (LeftFoot/LeftToeBase, CMU ASF lfoot/ltoes, l_foot/l_toes, LeftAnkle/LeftToe,
  // ...).
  std::vector<std::string> points{};
  double height_threshold = 0.03;  // m above the point's rest level to enter a plant
  double speed_threshold = 0.15;   // m/s horizontal to enter a plant
  // ... or this share of the point's own 90th-percentile horizontal speed when that is more, so
  // that runs get plants: their stance rolls faster than a walk's (0: speed_threshold alone).
  double speed_relative = 0.06;
  // ... or, where the body runs, this share of its horizontal speed at the frame when that is
  // more (0: none). A run's stance foot rolls and jitters at 0.2 to 1.5 m/s under a body at
  // 3.5 m/s, far slower than the body, while a swinging foot is faster. Such plants keep the
  // ends within body_relative x pace x min_duration_s of their median, where trim_distance is less.
  double body_relative = 0.35;
  // The body runs where the Froude number v^2 / (g h) of its pace passes this: v the horizontal
  // speed of the mean of its joints (over 0.2 s), h that mean's median height above the floor.
  // 0.5 is the walk-run transition of dynamic similarity (Alexander 1989), about 2.1 m/s for
  // an adult.
  double run_froude = 0.5;
  double hysteresis = 1.5;       // leave thresholds = enter thresholds * hysteresis (>= 1)
  double min_duration_s = 0.08;  // shorter spans are dropped
  int min_duration_frames = 3;   // and spans of fewer frames than this
  double floor = std::numeric_limits<double>::quiet_NaN();  // m; NaN: estimated
  double floor_percentile = 0.05;                           // in [0, 0.5]
  // With a given floor, every point's rest level is the floor itself instead of its own low
  // heights: for points on the sole (a foot's contact vertices), whose planted height is the
  // floor's. Ignored when the floor is estimated.
  bool rest_on_floor = false;
  double trim_distance = 0.01;  // m: a plant's end frames farther than this from its median
                                // position are trimmed off (0: no trimming)
  // Two plants of a point separated by a lift shorter than bridge_s (s; 0: none), where the point
  // comes back within bridge_distance (m, horizontal) of where it left, are one plant: a step's
  // swing lasts 0.2 s or more, so such a lift is the capture's jitter about a threshold.
  double bridge_s = 0.05;
  double bridge_distance = 0.03;
  double rest_window_s = 1.0;  // s, >= 0 (0: one rest level per point for the whole clip)
  int character = 0;           // written into the PointRefs
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

struct PlantPoint {
  std::string name;  // "LeftToeBase/end", "LeftFoot"
  PointRef point;
  double rest_height = 0;         // m, world: the floor_percentile of its heights (its clip-wide rest
                                  // level), or the given floor (rest_on_floor)
  std::vector<double> heights{};  // m, world: its height at every frame of the motion
  // m, world: at every frame, the level its height is measured above to detect plants (its
  // lowest height within rest_window_s around the frame, or rest_height).
  std::vector<double> rest_levels{};
};

struct Footplant {
  int point = 0;         // index into FootplantDetection::points
  int first_frame = 0;   // inclusive
  int last_frame = 0;    // inclusive
  Eigen::Vector3d mean;  // mean world position over the plant, metres
  double skate = 0;      // greatest horizontal distance from the first frame's position, m
};

struct FootplantDetection {
  std::vector<PlantPoint> points;
  std::vector<Footplant> plants;   // ordered by point, then time
  double floor = 0;                // m, world height of the floor (given or estimated)
  bool floor_estimated = false;    // floor was not given
  std::vector<std::string> notes;  // which points were chosen, floor estimate
  // Points that touch the floor but get no plant, while no other point of their foot (a joint
  // above or below theirs) is planted: one line each with the numbers (how long the point stays
  // within height_threshold of its rest level, and how fast it moves there). A run's ankle rolls
  // over its planted toe and is not warned of.
  std::vector<std::string> warnings;
  int count(int point) const;  // plants of one point
};

// Node-parameter text for the options above: "LeftFoot, RightToeBase/end" gives the names,
// trimmed, empty items dropped.
std::vector<std::string> split_names(const std::string& text);
// A `floor` parameter: "auto" or "" gives NaN (estimated), else a height in metres. Throws
// std::invalid_argument naming the text otherwise.
double parse_floor(const std::string& text);

// A point by the syntax of FootplantOptions::points ("Joint", "Joint/end", "Joint[x y z]") on
// `character`. Throws std::invalid_argument for an unknown joint (with the nearest name), a
// missing End Site or a malformed offset; `who` starts the messages ("footplants").
PlantPoint find_point(const Skeleton& skeleton, const std::string& spec, int character,
                      const std::string& who = "footplants");

// World positions (metres) of `points` at every frame of `motion`: frame_count() x points.size()
// entries, frame-major (frame f, point i at f * points.size() + i).
std::vector<Eigen::Vector3d> point_positions(const Motion& motion, const std::vector<PlantPoint>& points);

// Throws std::invalid_argument for a named joint that does not exist (with the nearest name),
// when no foot joint is found automatically, or for options out of range.
FootplantDetection detect_footplants(const Motion& motion, const FootplantOptions& options);

}  // namespace kg::motion
