// Motion file formats told apart by file extension: each format claims its extensions and
// brings a reader, a writer or both. io.import_motion and io.export_motion pick the format that
// claims a path's extension among those registered (kg.MotionFormat extensions, kg/io/nodes.hpp:
// the built-in BVH and ASF/AMC and any a plugin adds), so a new format plugs in without touching
// the dispatch.
//
//   const MotionFormats formats = builtin_motion_formats();
//   std::shared_ptr<const MotionFormat> bvh = motion_writer_for("out/walk.BVH", formats);
//   bvh->write(os, motion, {.units = "cm"});
//   ImportedMotion in = motion_reader_for("16_15.amc", formats)->read("16_15.amc", "16.asf", {});
#pragma once

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "kg/io/import_options.hpp"
#include "kg/motion/motion.hpp"

namespace kg::io {

// What every writer is asked for; a writer ignores what its format cannot express.
struct MotionWriteOptions {
  // Length unit written: "source" (the unit the clip was read in,
  // skeleton->source_unit_metres), "m", "cm", "mm" or "inch".
  std::string units = "source";
  int precision = 6;   // digits after the decimal point, 1..12 (trailing zeros dropped)
  bool exact = false;  // the skeleton's own channels rather than the layout every tool reads (bvh.hpp)
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// Reads the motion file `path` (and, for formats keeping the skeleton apart, `skeleton_path`:
// "" lets the reader find it or refuse) to skeleton.hpp's conventions. Throws kg::Error with
// file:line for a malformed file, std::invalid_argument for wrong arguments.
using MotionReader = std::function<ImportedMotion(const std::string& path, const std::string& skeleton_path,
                                                  const ImportOptions& options)>;
// Writes `motion` (metres, radians, +Y up) to `os` in the file's units and axes.
using MotionWriter =
    std::function<void(std::ostream& os, const motion::Motion& motion, const MotionWriteOptions& options)>;

struct MotionFormat {
  std::string name;                     // unique, shown in messages: "BVH", "ASF/AMC"
  std::vector<std::string> extensions;  // motion files it claims, with the dot: {".bvh"}; any case
  std::string skeleton_extension;       // its separate skeleton file's (".asf"); "" when none
  std::string doc;
  MotionReader read;   // empty: the format reads nothing
  MotionWriter write;  // empty: the format writes nothing
};

using MotionFormats = std::vector<std::shared_ptr<const MotionFormat>>;

// BVH (.bvh: reads and writes; bvh.hpp) and ASF/AMC (.amc with its .asf: reads; asf_amc.hpp).
std::shared_ptr<const MotionFormat> bvh_format();
std::shared_ptr<const MotionFormat> asf_amc_format();
// An ASF skeleton alone (.asf: reads its rest pose as a one-frame clip, e.g. a retargeting
// target or `kinegraph map`'s).
std::shared_ptr<const MotionFormat> asf_format();
// URDF (.urdf: reads a robot's tree as a one-frame clip; urdf.hpp), and a robot's motion written
// as .csv or .json (robot_motion.hpp; a motion on a URDF's skeleton).
std::shared_ptr<const MotionFormat> urdf_format();
std::shared_ptr<const MotionFormat> robot_csv_format();
std::shared_ptr<const MotionFormat> robot_json_format();
// {asf_amc_format(), asf_format(), bvh_format(), urdf_format(), robot_csv_format(),
// robot_json_format()}
MotionFormats builtin_motion_formats();

// The one format of `formats` that reads (writes) files named like `path`, by its extension
// compared case-insensitively (null entries are skipped). Throws std::invalid_argument naming
// the file and what is available when none does:
//   "x.fbx: no motion writer claims '.fbx'; writers: .bvh (BVH); readers: .amc (ASF/AMC,
//    skeleton .asf), .bvh (BVH)"
// (a reader's message lists the readers first), and naming both when two formats do.
std::shared_ptr<const MotionFormat> motion_reader_for(const std::string& path, const MotionFormats& formats);
std::shared_ptr<const MotionFormat> motion_writer_for(const std::string& path, const MotionFormats& formats);

// motion_reader_for(path, formats)->read(path, skeleton_path, options): a .bvh or an .amc with
// the built-in formats. For an .amc, `skeleton_path` is its .asf; when empty, guess_asf_for_amc's
// answer is used and said in the notes, and without one the call throws std::invalid_argument
// asking for the skeleton. For a .bvh, skeleton_path must be empty.
ImportedMotion import_motion(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options, const MotionFormats& formats);
ImportedMotion import_motion(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options);

}  // namespace kg::io
