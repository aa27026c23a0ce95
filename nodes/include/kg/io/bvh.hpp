// Biovision Hierarchy (BVH) files: a strict, fast reader and a writer.
//
// The reader keeps the file as it is: lengths in the FILE's unit, the file's axes, OFFSETs and
// channel orders as written (position channels replace the matching OFFSET components, the
// convention of skeleton.hpp, Blender and MotionBuilder); only angles become radians. Call
// apply_import_options (import_options.hpp) to bring the clip to metres and +Y up, or use
// import_bvh, which does both.
//
//   ImportedMotion in = import_bvh("walk.bvh", {.units = "auto"});           // metres, radians
//   for (const std::string& note : in.notes) std::cerr << note << '\n';      // what auto chose
//   write_bvh(os, in.motion, BvhWriteOptions{.units = "cm", .precision = 6});
//
// Errors: any malformed or truncated file throws kg::Error whose what() is
// "file:line:column: expected ..., got ...". Nothing is read past the end of the text.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "kg/io/import_options.hpp"
#include "kg/motion/motion.hpp"

namespace kg::io {

// A BVH file as written in it.
struct BvhClip {
  // Lengths (OFFSETs, End Sites, position channel values) in file units, file axes
  // (skeleton->source_unit_metres == 1, file_to_world == identity); rotation channels in
  // radians; fps = motion::rate_of_printed_frame_time of the header (frame_time.hpp: 30, not
  // 30.00003, for "0.0333333"); name = the file's stem. Joints in file order (depth first),
  // so channel i of a frame is the i-th value of its line.
  motion::Motion motion;
  double frame_time = 0;  // seconds per frame, as the header's "Frame Time:" says
};

// The frame times parse_bvh accepts, in seconds: 1 microsecond (1e6 fps) to an hour per frame,
// so 1 / frame_time is a finite, sane frame rate.
inline constexpr double kBvhMinFrameTime = 1e-6;
inline constexpr double kBvhMaxFrameTime = 3600;

// Parses BVH text. `file_name` only names the file in error messages and gives motion.name.
// Accepts: any channel order and count (0..6, no channel twice) per joint, position channels
// on any joint, End Sites, several ROOTs, LF or CRLF line ends, blanks and tabs, keywords and
// channel names in any letter case, a UTF-8 BOM. Refuses (kg::Error): missing
// HIERARCHY/ROOT/MOTION/Frames:/Frame Time:, unknown or repeated channel names, CHANNELS n not
// followed by exactly n names on its line, unbalanced braces, a non-numeric, NaN or infinite
// number, a frame time outside kBvhMinFrameTime..kBvhMaxFrameTime, a frame line with too few or too many
// values, fewer frame lines than "Frames:" says or anything but blanks after the last one, duplicate joint
// names.
BvhClip parse_bvh(std::string_view text, const std::string& file_name);

// Reads the whole file at once and parses it; an unreadable file throws kg::Error
// naming it.
BvhClip read_bvh(const std::filesystem::path& path);

// read_bvh followed by apply_import_options; file_frame_time is the header's "Frame Time:".
ImportedMotion import_bvh(const std::filesystem::path& path, const ImportOptions& options);

struct BvhWriteOptions {
  // Unit of the written lengths: source (the skeleton's source_unit_metres) | m | cm | mm |
  // inch | asf.
  std::string units = "source";
  // Digits after the decimal point of every value (1..12); trailing zeros are dropped.
  int precision = 6;
  // false: every joint has three rotation channels, and three position channels when it has
  // any, as Blender and MotionBuilder read BVH (a 2-channel ASF clavicle gets its third axis,
  // a lone Yposition its X and Z from the OFFSET). true: the skeleton's own channels.
  bool exact = false;
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// Writes `motion` (skeleton.hpp's conventions) as BVH: file axes (file_to_world is not
// applied: it sits above the roots, so channels and offsets already are file coordinates),
// degrees, the skeleton's channel orders, joints depth first (roots and children in index
// order), End Sites after a joint's children, "Frame Time" = 1 / fps with 9 significant digits.
// A joint whose `axis` is not the identity (ASF bones) cannot be said in BVH, nor, unless
// options.exact, one with other than three rotation channels: it is written with three
// rotation channels (its own rotation axes first, in their order, then the missing ones in X, Y,
// Z order) holding the Euler angles of axis * R * axis^T; position channels are kept (made three
// unless exact). Joint limits are not written. Throws std::invalid_argument on bad options or a motion
// failing Motion::check().
void write_bvh(std::ostream& os, const motion::Motion& motion, const BvhWriteOptions& options = {});
std::string write_bvh_string(const motion::Motion& motion, const BvhWriteOptions& options = {});

}  // namespace kg::io
