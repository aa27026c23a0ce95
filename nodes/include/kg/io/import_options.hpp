// What every motion importer takes from a user, because real files lie about their units, up
// axis and frame rate (../shared/data/README.md). Importers read a file in its own units and
// axes, then call apply_import_options to bring the clip to skeleton.hpp's conventions.
//
//   ImportOptions opt{.units = "auto", .up = "auto", .fps = 0};
//   std::vector<std::string> notes = apply_import_options(motion, opt, file_fps, "walk.bvh");
//   // notes: {"walk.bvh: units auto: standing height 172.3 file units, taken as cm (1.72 m)"}
//   ImportedMotion in = import_bvh("walk.bvh", opt);  // bvh.hpp; import_asf_amc the same
#pragma once

#include <string>
#include <vector>

#include "kg/motion/motion.hpp"

namespace kg::io {

struct ImportOptions {
  // auto | m | cm | mm | inch | asf (ASF's default `length 0.45` inches unit, 2.54/45 m).
  // auto: the file's own declaration when it has one (ASF :units), else guessed from standing
  // height, and said so in the notes.
  std::string units = "auto";
  // auto | y | z: which file axis points up; auto guesses from the posed figure's extents
  // (the rule: apply_import_options below).
  std::string up = "auto";
  // Frames per second overriding the file's header; 0 keeps the file's.
  double fps = 0;
  // With fps 0: the rate the clip's free-fall flights imply when it is the header's times a
  // whole factor (motion::rate_from_flights, kg/motion/inspect.hpp), said in a note either way;
  // the header's otherwise. A graph's `source_fps: auto`.
  bool fps_from_flights = false;
  // auto | none | FIRST..LAST | FIRST.. (frame numbers of the file, from 0, inclusive): the
  // frames kept. auto drops calibration frames (a T-pose or A-pose before the motion starts:
  // motion::detect_calibration_frames, kg/motion/calibration.hpp) and says so either way.
  std::string trim = "auto";
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// What every importer returns (import_bvh, import_asf_amc, import_motion): a clip brought to
// skeleton.hpp's conventions and what was done to get there.
struct ImportedMotion {
  motion::Motion motion;           // metres, radians, +Y up (skeleton.hpp's conventions)
  std::vector<std::string> notes;  // one line each, for the user: what `auto` chose, fps assumed...
  // Seconds per frame as the file's header states it (BVH's "Frame Time:"); motion.fps may
  // override it. 0 when the file states none (AMC).
  double file_frame_time = 0;
};

// The frames `trim` keeps of a clip of `frames` frames: [first, last], inclusive; auto and none
// give [0, frames-1] (auto's cut is made by apply_import_options). Throws std::invalid_argument
// for a malformed value or one outside the clip.
struct FrameRange {
  int first = 0, last = -1;
};
FrameRange trim_range(const std::string& trim, int frames);

// Right-handed rotation taking +Z to +Y: -90 degrees about X, (x, y, z) -> (x, z, -y); the
// file_to_world of a Z-up file.
Eigen::Matrix3d z_up_to_y_up();

// Metres per unit for a units name other than auto; throws std::invalid_argument otherwise.
double metres_per_unit(const std::string& units);
// Whether metres_per_unit knows `units`.
bool known_unit(const std::string& units);

// Brings `motion`, read in its file's units and axes (lengths in file units, file_to_world
// identity, angles already radians), to skeleton.hpp's conventions, in place:
//   - units: OFFSETs, End Sites, position channel values and position channel limits are
//     multiplied by the unit's metres; skeleton->source_unit_metres is set to it. `auto` takes
//     `declared_metres_per_unit` when > 0 (a unit the file states, as ASF's :units), else the
//     named unit (m, cm, mm, inch, asf) that makes the standing height closest to 1.7 m,
//     preferring those giving 0.5..2.3 m (a newborn, or a small character, to the tallest
//     adults; another unit giving such a height is named in the note). Standing height = the larger of the
//     extents along the up axis of joints and End Sites in the rest pose (OFFSETs only) and in frame 0.
//   - up: `z` sets file_to_world to the right-handed rotation taking +Z to +Y (-90 deg about
//     X: (x, y, z) -> (x, z, -y)); `y` keeps the identity. `auto` takes the extents along Y and
//     Z of joints and End Sites in 9 frames spread evenly over the clip (frame 0 and the last
//     included; the rest pose when there is no frame), their medians over those frames, and
//     picks z when Z's median exceeds Y's by more than 20 %, else y (BVH's usual convention,
//     also when undecided). Posed frames rather than the rest pose, because files rotate their
//     root (iClone's Z-up rig under a -90 deg root) or orient bones along X (Bandai): the posed
//     figure is what a viewer shows; a median, because a single pose (arms reaching forward)
//     can be as deep as it is tall.
//   - fps: options.fps when > 0, else file_fps (which must then be > 0); with fps_from_flights,
//     then what the flights imply (before trim: calibration speeds are per second).
//   - trim (last, on the converted clip): auto drops the frames detect_calibration_frames
//     finds; FIRST..LAST keeps those frames (LAST past the clip is an error naming the clip's
//     frame count); none keeps all. Frame numbers in later files (constraints, contacts) count
//     from the first frame kept.
// Channel values other than position channels are not touched: file_to_world sits above the
// roots, so channels stay in file coordinates and exporters write them back unchanged.
// Returns notes for the user, each starting with "file_name: ", saying what auto chose (and
// from what), a fps override, or an implausible height. The skeleton is replaced by a
// converted copy (the old one may be shared). Throws std::invalid_argument on a bad option
// name, fps < 0, or no fps at all.
std::vector<std::string> apply_import_options(motion::Motion& motion, const ImportOptions& options,
                                              double file_fps, const std::string& file_name,
                                              double declared_metres_per_unit = 0);

// "m", "cm", "mm", "inch" or "asf" when `metres_per_unit` is one of those (to 1e-9 relative),
// else the number of metres ("0.0078125 m"). For messages and reports.
std::string unit_name(double metres_per_unit);

// "y" for an identity file_to_world, "z" for apply_import_options' Z-up rotation, else "custom".
std::string up_axis_name(const Eigen::Matrix3d& file_to_world);

}  // namespace kg::io
