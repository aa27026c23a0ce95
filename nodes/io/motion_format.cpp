// The built-in motion formats and the dispatch by file extension (motion_format.hpp).
#include "kg/io/motion_format.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/robot_motion.hpp"
#include "kg/io/urdf.hpp"

namespace kg::io {

namespace {

std::string file_name_of(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

ImportedMotion read_bvh_file(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options) {
  if (!skeleton_path.empty()) {
    throw std::invalid_argument(path + ": a BVH file holds its own skeleton; expected skeleton \"\", got \"" +
                                skeleton_path + "\"");
  }
  return import_bvh(path, options);
}

ImportedMotion read_amc_file(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options) {
  std::string asf = skeleton_path;
  std::vector<std::string> notes;
  if (asf.empty()) {
    // A missing .amc is what is wrong, not the skeleton that cannot be guessed beside it.
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw kg::Error("no such AMC file", {path});
    asf = guess_asf_for_amc(path);
    if (asf.empty()) {
      throw std::invalid_argument(
          path +
          ": an AMC file needs its skeleton: set skeleton to the .asf file (none found "
          "by the subject prefix of the name, e.g. 16_15.amc -> 16.asf)");
    }
    notes.push_back(file_name_of(path) + ": skeleton not given; using " + asf +
                    " (the subject prefix of the name)");
  }
  ImportedMotion out = import_asf_amc(asf, path, options);
  out.notes.insert(out.notes.begin(), notes.begin(), notes.end());
  return out;
}

// An ASF alone: its rest pose as one frame (every channel zero), at the AMC default rate.
ImportedMotion read_asf_file(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options) {
  if (!skeleton_path.empty()) {
    throw std::invalid_argument(
        path + ": an ASF file is the skeleton itself; expected skeleton \"\", got \"" + skeleton_path + "\"");
  }
  options.validate();
  const AsfSkeleton asf = read_asf(path);
  ImportedMotion out;
  out.motion = motion::Motion{asf.skeleton, motion::FrameMatrix::Zero(1, asf.skeleton->channel_count()),
                              kAmcDefaultFps, std::filesystem::path(path).stem().string()};
  out.notes = apply_import_options(out.motion, options, kAmcDefaultFps, path,
                                   asf.declared_metres_per_unit().value_or(0.0));
  out.notes.push_back(file_name_of(path) + ": an ASF skeleton alone: one frame, its rest pose");
  return out;
}

ImportedMotion read_urdf_file(const std::string& path, const std::string& skeleton_path,
                              const ImportOptions& options) {
  if (!skeleton_path.empty()) {
    throw std::invalid_argument(path + ": a URDF file holds its own tree; expected skeleton \"\", got \"" +
                                skeleton_path + "\"");
  }
  return import_urdf(path, options);
}

ImportedMotion read_robot_csv_file(const std::string& path, const std::string& skeleton_path,
                                   const ImportOptions& options) {
  options.validate();
  if (skeleton_path.empty()) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw kg::Error("no such robot CSV file", {path});
    throw std::invalid_argument(path + ": a robot CSV needs its robot: set skeleton to the .urdf");
  }
  if (options.units != "auto" && options.units != "m")
    throw std::invalid_argument(path + ": a robot CSV is in metres; expected units auto or m, got " +
                                text::excerpt(options.units));
  if (options.up != "auto" && options.up != "z")
    throw std::invalid_argument(path + ": a robot CSV is Z up, as its URDF; expected up auto or z, got " +
                                text::excerpt(options.up));
  const Robot robot = read_urdf(skeleton_path);
  ImportedMotion out;
  out.motion = parse_robot_csv(read_input_file(path, "robot CSV file"), path, robot, options.fps);
  // Its units and axes are the URDF's; only an explicit frame range applies (auto has no
  // calibration pose to find on a robot).
  if (options.trim != "auto" && options.trim != "none") {
    const FrameRange keep = trim_range(options.trim, out.motion.frame_count());
    out.motion = motion::frame_range(out.motion, keep.first, keep.last);
  }
  out.notes.push_back(file_name_of(path) + ": a robot CSV on " + file_name_of(skeleton_path) + ", " +
                      std::to_string(out.motion.frame_count()) + " frames at " +
                      text::significant(out.motion.fps) + " fps" +
                      (options.fps > 0 ? " (source_fps)" : " (from its time column)") + "; Z up, metres");
  return out;
}

}  // namespace

void MotionWriteOptions::validate() const {
  using options::require;
  const char* o = "MotionWriteOptions";
  require(units == "source" || known_unit(units), o, "units", units, "source, m, cm, mm, inch or asf");
  require(precision >= 1 && precision <= 12, o, "precision", precision,
          "1 to 12 digits after the decimal point");
}

namespace {

void write_bvh_file(std::ostream& os, const motion::Motion& motion, const MotionWriteOptions& options) {
  options.validate();
  write_bvh(os, motion,
            BvhWriteOptions{.units = options.units, .precision = options.precision, .exact = options.exact});
}

bool claims(const MotionFormat& format, const std::string& lower_ext) {
  return std::any_of(format.extensions.begin(), format.extensions.end(),
                     [&](const std::string& e) { return text::ascii_lower(e) == lower_ext; });
}

// ".amc (ASF/AMC, skeleton .asf), .bvh (BVH)": every extension of the formats that read (or
// write), sorted; "none" when there is none.
std::string listing(const MotionFormats& formats, bool readers) {
  std::vector<std::string> items;
  for (const auto& f : formats) {
    if (!f || !(readers ? static_cast<bool>(f->read) : static_cast<bool>(f->write))) continue;
    const std::string what =
        readers && !f->skeleton_extension.empty() ? f->name + ", skeleton " + f->skeleton_extension : f->name;
    for (const std::string& e : f->extensions) items.push_back(text::ascii_lower(e) + " (" + what + ")");
  }
  if (items.empty()) return "none";
  std::sort(items.begin(), items.end());
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

std::shared_ptr<const MotionFormat> format_for(const std::string& path, const MotionFormats& formats,
                                               bool reading) {
  const std::string ext = text::lower_extension(path);
  const char* role = reading ? "reader" : "writer";
  std::vector<std::shared_ptr<const MotionFormat>> found;
  if (!ext.empty())
    for (const auto& f : formats)
      if (f && (reading ? static_cast<bool>(f->read) : static_cast<bool>(f->write)) && claims(*f, ext))
        found.push_back(f);
  if (found.size() == 1) return found.front();

  const std::string available =
      reading ? "readers: " + listing(formats, true) + "; writers: " + listing(formats, false)
              : "writers: " + listing(formats, false) + "; readers: " + listing(formats, true);
  if (found.empty()) {
    const std::string what = ext.empty() ? std::string("a file without an extension") : text::excerpt(ext);
    throw std::invalid_argument(text::shown_path(path) + ": no motion " + role + " claims " + what + "; " +
                                available);
  }
  std::string names;
  for (const auto& f : found) names += (names.empty() ? "" : " and ") + f->name;
  throw std::invalid_argument(text::shown_path(path) + ": " + text::excerpt(ext) + " is claimed by " +
                              std::to_string(found.size()) + " motion " + role + "s, " + names + "; " +
                              available);
}

}  // namespace

std::shared_ptr<const MotionFormat> bvh_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "BVH",
      .extensions = {".bvh"},
      .skeleton_extension = {},
      .doc = "Biovision hierarchy: the skeleton and its channels in one text file (bvh.hpp)",
      .read = &read_bvh_file,
      .write = &write_bvh_file,
  });
}

std::shared_ptr<const MotionFormat> asf_amc_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "ASF/AMC",
      .extensions = {".amc"},
      .skeleton_extension = ".asf",
      .doc = "Acclaim motion (.amc) on its skeleton (.asf), as in the CMU database (asf_amc.hpp)",
      .read = &read_amc_file,
      .write = {},
  });
}

std::shared_ptr<const MotionFormat> asf_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "ASF skeleton",
      .extensions = {".asf"},
      .skeleton_extension = {},
      .doc = "an Acclaim skeleton (.asf) alone: one frame, its rest pose (asf_amc.hpp)",
      .read = &read_asf_file,
      .write = {},
  });
}

std::shared_ptr<const MotionFormat> urdf_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "URDF",
      .extensions = {".urdf"},
      .skeleton_extension = {},
      .doc = "a robot's tree (urdfdom): one frame with every joint at zero (urdf.hpp)",
      .read = &read_urdf_file,
      .write = {},
  });
}

std::shared_ptr<const MotionFormat> robot_csv_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "robot CSV",
      .extensions = {".csv"},
      .skeleton_extension = ".urdf",
      .doc = "a robot's motion: time, the floating base (Z up, quaternion x y z w) and each degree of "
             "freedom, one row per frame, on its robot's .urdf (robot_motion.hpp)",
      .read = &read_robot_csv_file,
      .write =
          [](std::ostream& os, const motion::Motion& motion, const MotionWriteOptions& options) {
            options.validate();
            write_robot_csv(os, robot_trajectory(motion), options.precision);
          },
  });
}

std::shared_ptr<const MotionFormat> robot_json_format() {
  return std::make_shared<const MotionFormat>(MotionFormat{
      .name = "robot JSON",
      .extensions = {".json"},
      .skeleton_extension = {},
      .doc = "a robot's motion as fps, joint_names, root_pos, root_rot and dof_pos arrays (GMR's fields; "
             "robot_motion.hpp)",
      .read = {},
      .write =
          [](std::ostream& os, const motion::Motion& motion, const MotionWriteOptions& options) {
            options.validate();
            write_robot_json(os, robot_trajectory(motion));
          },
  });
}

MotionFormats builtin_motion_formats() {
  return {asf_amc_format(), asf_format(),       bvh_format(),
          urdf_format(),    robot_csv_format(), robot_json_format()};
}

std::shared_ptr<const MotionFormat> motion_reader_for(const std::string& path, const MotionFormats& formats) {
  return format_for(path, formats, true);
}

std::shared_ptr<const MotionFormat> motion_writer_for(const std::string& path, const MotionFormats& formats) {
  return format_for(path, formats, false);
}

ImportedMotion import_motion(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options, const MotionFormats& formats) {
  return motion_reader_for(path, formats)->read(path, skeleton_path, options);
}

ImportedMotion import_motion(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options) {
  return import_motion(path, skeleton_path, options, builtin_motion_formats());
}

}  // namespace kg::io
