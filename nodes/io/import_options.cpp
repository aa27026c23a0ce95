#include "kg/io/import_options.hpp"
#include "kg/base/error.hpp"
#include "kg/base/option_check.hpp"
#include "kg/base/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "kg/motion/calibration.hpp"
#include "kg/motion/inspect.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::io {
namespace {

using motion::Skeleton;

struct NamedUnit {
  const char* name;
  double metres;
};

// Order matters only for ties in the auto guess (none occur between these factors).
constexpr NamedUnit kUnits[] = {
    {"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"inch", 0.0254}, {"asf", 0.0254 / 0.45},
};

// A standing adult: what `auto` aims at; and the band of human heights it calls plausible, from a
// newborn (or a character a retargeting made 0.6 of a small adult) to the tallest adults.
constexpr double kTypicalHeight = 1.7;
constexpr double kPlausibleMin = 0.5;
constexpr double kPlausibleMax = 2.3;
// `auto` up picks z only when Z's extent exceeds Y's by this factor, and looks at this many
// frames spread through the clip.
constexpr double kUpMargin = 1.2;
constexpr int kUpSamples = 9;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

// Min and max along each file axis of joint origins and End Sites.
struct Extent {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  void add(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  double along(int axis) const { return hi[axis] >= lo[axis] ? hi[axis] - lo[axis] : 0.0; }
};

// Rest pose: OFFSETs only, no channel applied (translations as the hierarchy states them).
// Joints marked in `skip` (a static root chain) and their End Sites are left out.
Extent rest_extent(const Skeleton& s, const std::vector<bool>& skip) {
  Extent e;
  std::vector<Eigen::Vector3d> pos(static_cast<std::size_t>(s.joint_count()));
  for (int j = 0; j < s.joint_count(); ++j) {
    const motion::Joint& joint = s.joint(j);
    pos[j] = joint.parent < 0 ? joint.offset : Eigen::Vector3d(pos[joint.parent] + joint.offset);
    if (skip[static_cast<std::size_t>(j)]) continue;
    e.add(pos[j]);
    for (const Eigen::Vector3d& tip : joint.end_sites) e.add(pos[j] + tip);
  }
  return e;
}

// One frame posed, in file coordinates (file_to_world undone), without the joints in `skip`.
Extent frame_extent(const motion::Motion& m, int frame, const std::vector<bool>& skip) {
  const Skeleton& s = *m.skeleton;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  motion::forward_kinematics(s, m.values.row(frame), world);
  const Eigen::Matrix3d to_file = s.file_to_world.transpose();
  Extent e;
  for (int j = 0; j < s.joint_count(); ++j) {
    if (skip[static_cast<std::size_t>(j)]) continue;
    e.add(to_file * world[j].translation());
    for (const Eigen::Vector3d& tip : s.joint(j).end_sites) e.add(to_file * (world[j] * tip));
  }
  return e;
}

// The frames the up axis is judged on: kUpSamples spread through the clip, first and last included.
std::vector<int> sampled_frames(int frames) {
  std::vector<int> out;
  const int samples = std::min(frames, kUpSamples);
  for (int k = 0; k < samples; ++k)
    out.push_back(samples == 1 ? 0
                               : static_cast<int>((static_cast<long long>(frames - 1) * k) / (samples - 1)));
  return out;
}

// A static root chain: from the single root down, each joint with one child that stays at one
// place in every sampled frame (an exporter's "Root" at the origin while its Hips child carries
// the translation). Its origin is no part of the figure: left in, a walk away from it spans metres
// along the walking direction in every frame. Returns the mask (true: skipped) and their names.
std::pair<std::vector<bool>, std::string> static_root_chain(const motion::Motion& m) {
  const Skeleton& s = *m.skeleton;
  std::vector<bool> skip(static_cast<std::size_t>(s.joint_count()), false);
  std::string names;
  std::vector<std::vector<int>> children(static_cast<std::size_t>(s.joint_count()));
  std::vector<int> roots;
  for (int j = 0; j < s.joint_count(); ++j)
    (s.joint(j).parent < 0 ? roots : children[static_cast<std::size_t>(s.joint(j).parent)]).push_back(j);
  if (roots.size() != 1 || m.frame_count() == 0) return {skip, names};
  std::vector<std::vector<Eigen::Isometry3d>> posed;
  for (int f : sampled_frames(m.frame_count())) {
    posed.emplace_back(static_cast<std::size_t>(s.joint_count()));
    motion::forward_kinematics(s, m.values.row(f), posed.back());
  }
  for (int j = roots.front(); children[static_cast<std::size_t>(j)].size() == 1;
       j = children[static_cast<std::size_t>(j)].front()) {
    const Eigen::Vector3d first = posed.front()[static_cast<std::size_t>(j)].translation();
    double moved = 0, size = first.norm();
    for (const auto& world : posed) {
      moved = std::max(moved, (world[static_cast<std::size_t>(j)].translation() - first).norm());
      size = std::max(size, world[static_cast<std::size_t>(j)].translation().norm());
    }
    if (moved > 1e-9 * std::max(1.0, size)) break;
    skip[static_cast<std::size_t>(j)] = true;
    names += (names.empty() ? "" : ", ") + text::in_quotes(s.joint(j).name);
  }
  return {skip, names};
}

// Offsets, end sites and values all finite (converting units can overflow absurd numbers).
bool lengths_finite(const motion::Skeleton& skeleton, const motion::FrameMatrix& values) {
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const motion::Joint& joint = skeleton.joint(j);
    if (!joint.offset.allFinite()) return false;
    for (const Eigen::Vector3d& tip : joint.end_sites)
      if (!tip.allFinite()) return false;
  }
  return values.allFinite();
}

// A frame number of a trim value: digits only, at most 9 of them (no overflow, no sign).
bool parse_frame_number(const std::string& text, int& out) {
  if (text.empty() || text.size() > 9) return false;
  for (char c : text)
    if (c < '0' || c > '9') return false;
  out = std::stoi(text);
  return true;
}

// FIRST..LAST or FIRST.. parsed; last = -1 for an open end. False when malformed.
bool parse_trim(const std::string& trim, int& first, int& last) {
  const std::size_t dots = trim.find("..");
  if (dots == std::string::npos) return false;
  const std::string a = trim.substr(0, dots), b = trim.substr(dots + 2);
  if (!parse_frame_number(a, first)) return false;
  last = -1;
  if (!b.empty() && !parse_frame_number(b, last)) return false;
  return last < 0 || last >= first;
}

const char* kTrimExpected = "auto, none, FIRST..LAST or FIRST.. (frame numbers from 0, FIRST <= LAST)";

// Keeps rows [first, last] of the clip's values.
void keep_frames(motion::Motion& m, int first, int last) {
  motion::FrameMatrix kept = m.values.middleRows(first, last - first + 1);
  m.values = std::move(kept);
}

}  // namespace

Eigen::Matrix3d z_up_to_y_up() {
  Eigen::Matrix3d r;
  r << 1, 0, 0,  //
      0, 0, 1,   //
      0, -1, 0;
  return r;
}

FrameRange trim_range(const std::string& trim, int frames) {
  if (trim == "auto" || trim == "none") return {0, frames - 1};
  int first = 0, last = -1;
  if (!parse_trim(trim, first, last))
    throw std::invalid_argument("trim " + text::excerpt(trim) + ": expected " + kTrimExpected);
  if (last < 0) last = frames - 1;
  if (first >= frames || last >= frames)
    throw std::invalid_argument("trim " + trim + ": the clip has " + std::to_string(frames) + " frames (0.." +
                                std::to_string(frames - 1) + ")");
  return {first, last};
}

double metres_per_unit(const std::string& units) {
  for (const NamedUnit& u : kUnits)
    if (units == u.name) return u.metres;
  throw std::invalid_argument("unknown units " + text::in_quotes(units) +
                              " (expected m, cm, mm, inch or asf)");
}

std::string unit_name(double metres) {
  for (const NamedUnit& u : kUnits)
    if (std::abs(metres - u.metres) <= 1e-9 * u.metres) return u.name;
  return fmt("%.9g m", metres);
}

std::string up_axis_name(const Eigen::Matrix3d& file_to_world) {
  if (file_to_world.isApprox(Eigen::Matrix3d::Identity(), 1e-12)) return "y";
  if (file_to_world.isApprox(z_up_to_y_up(), 1e-12)) return "z";
  return "custom";
}

bool known_unit(const std::string& units) {
  for (const NamedUnit& u : kUnits)
    if (units == u.name) return true;
  return false;
}

void ImportOptions::validate() const {
  using options::require;
  const char* o = "ImportOptions";
  require(units == "auto" || known_unit(units), o, "units", units, "auto, m, cm, mm, inch or asf");
  require(up == "auto" || up == "y" || up == "z", o, "up", up, "auto, y or z");
  require(options::non_negative(fps), o, "fps", fps,
          ">= 0 and finite (frames per second; 0 keeps the file's)");
  int first = 0, last = 0;
  require(trim == "auto" || trim == "none" || parse_trim(trim, first, last), o, "trim", text::excerpt(trim),
          kTrimExpected);
}

std::vector<std::string> apply_import_options(motion::Motion& m, const ImportOptions& options,
                                              double file_fps, const std::string& file_name,
                                              double declared_metres_per_unit) {
  options.validate();
  if (options.fps == 0 && !(file_fps > 0 && std::isfinite(file_fps)))
    throw std::invalid_argument(file_name + ": the file gives no frame rate; set fps");
  if (!m.skeleton) throw std::invalid_argument(file_name + ": motion has no skeleton");

  std::vector<std::string> notes;
  const std::string prefix = file_name + ": ";
  auto skeleton = std::make_shared<Skeleton>(*m.skeleton);
  skeleton->file_to_world = Eigen::Matrix3d::Identity();
  m.skeleton = skeleton;  // frame_extent reads it

  const auto [skip, static_roots] = static_root_chain(m);
  const Extent rest = rest_extent(*skeleton, skip);
  const bool has_frames = m.frame_count() > 0;
  const Extent posed = has_frames ? frame_extent(m, 0, skip) : rest;

  // Up axis.
  int up = 1;
  if (options.up == "z") {
    up = 2;
  } else if (options.up == "auto") {
    // Median extents over frames spread through the clip: one pose (a dancer's arms reaching
    // forward, a crouch) can be as deep as it is tall, most poses of a clip are not.
    double ey = rest.along(1), ez = rest.along(2);
    std::string pose = "the rest pose";
    if (has_frames) {
      const std::vector<int> frames = sampled_frames(m.frame_count());
      std::vector<double> ys, zs;
      for (int f : frames) {
        const Extent e = f == 0 ? posed : frame_extent(m, f, skip);
        ys.push_back(e.along(1));
        zs.push_back(e.along(2));
      }
      ey = median(ys);
      ez = median(zs);
      pose = frames.size() == 1 ? std::string("frame 0")
                                : "the median of " + std::to_string(frames.size()) + " frames";
    }
    std::string spans =
        pose + " spans " + fmt("%.4g", ey) + " along Y and " + fmt("%.4g", ez) + " along Z (file units)";
    if (!static_roots.empty())
      spans += " without the static root joint(s) " + static_roots + " (at one place in every frame)";
    if (ez > kUpMargin * ey) {
      up = 2;
      notes.push_back(prefix + "up auto: " + spans + ", taken as Z up");
    } else if (ey > kUpMargin * ez) {
      notes.push_back(prefix + "up auto: " + spans + ", taken as Y up");
    } else {
      notes.push_back(prefix + "up auto: " + spans + ", undecided: taken as Y up (BVH's convention)");
    }
  }
  if (up == 2) skeleton->file_to_world = z_up_to_y_up();

  // Units.
  const double height = std::max(rest.along(up), posed.along(up));
  double mpu = 1.0;
  if (options.units == "auto") {
    if (declared_metres_per_unit > 0) {
      mpu = declared_metres_per_unit;
      notes.push_back(prefix + "units auto: the file declares " + unit_name(mpu) + " (" + fmt("%.9g", mpu) +
                      " m per unit); standing height " +
                      fmt(std::abs(height * mpu) < 1e4 ? "%.3f" : "%.3g", height * mpu) + " m");
    } else if (!(height > 0)) {
      notes.push_back(prefix + "units auto: the figure has no height along the up axis, taken as m");
    } else {
      const NamedUnit* best = nullptr;
      double best_score = std::numeric_limits<double>::infinity();
      for (const NamedUnit& u : kUnits) {
        const double h = height * u.metres;
        const bool plausible = h >= kPlausibleMin && h <= kPlausibleMax;
        const double score = std::abs(std::log(h / kTypicalHeight)) + (plausible ? 0.0 : 1e3);
        if (score < best_score) best_score = score, best = &u;
      }
      mpu = best->metres;
      const double h = height * mpu;
      std::string note = prefix + "units auto: standing height " + fmt("%.4g", height) +
                         " file units, taken as " + best->name + " (" +
                         fmt(std::abs(h) < 1e4 ? "%.2f" : "%.3g", h) + " m)";
      if (h < kPlausibleMin || h > kPlausibleMax)
        note += "; no unit gives a human height of " + fmt("%.1f", kPlausibleMin) + ".." +
                fmt("%.1f", kPlausibleMax) + " m, this one comes closest: set units if it is wrong";
      // Another human height: the clip cannot tell (a retargeted figure keeps its source's timing,
      // so neither its flights nor its gait say its size); the user can.
      for (const NamedUnit& u : kUnits) {
        const double other = height * u.metres;
        if (&u != best && other >= kPlausibleMin && other <= kPlausibleMax)
          note += "; " + std::string(u.name) + " would make it " + fmt("%.2f", other) +
                  " m: set units=" + u.name + " if it is";
      }
      notes.push_back(note);
    }
  } else {
    mpu = metres_per_unit(options.units);
    const double h = height * mpu;
    if (height > 0 && (h < kPlausibleMin || h > kPlausibleMax))
      notes.push_back(prefix + "units " + options.units + ": the figure stands " + fmt("%.3g", h) +
                      " m tall, not a human height: check the units");
  }

  skeleton->source_unit_metres = mpu;
  if (mpu != 1.0) {
    for (int j = 0; j < skeleton->joint_count(); ++j) {
      motion::Joint& joint = skeleton->joint_mut(j);
      joint.offset *= mpu;
      for (Eigen::Vector3d& tip : joint.end_sites) tip *= mpu;
      for (std::size_t c = 0; c < joint.channels.size(); ++c) {
        motion::Channel& ch = joint.channels[c];
        if (motion::is_rotation(ch.kind)) continue;
        ch.min *= mpu;  // infinities stay infinite
        ch.max *= mpu;
        // Not on a clip without frames: a column of a row-major 0 x n matrix offsets its null data.
        if (has_frames) m.values.col(joint.first_channel + static_cast<int>(c)) *= mpu;
      }
    }
  }

  if (!lengths_finite(*skeleton, m.values))
    throw kg::Error("lengths overflow converted to metres (" + fmt("%g", mpu) +
                        " m per file unit): check the units and the file's numbers",
                    {file_name});

  // Frame rate.
  if (options.fps > 0) {
    if (file_fps > 0)
      notes.push_back(prefix + "fps " + fmt("%g", options.fps) + " from the options; the file says " +
                      fmt("%.6g", file_fps));
    m.fps = options.fps;
  } else {
    m.fps = file_fps;
  }
  if (options.fps_from_flights && options.fps == 0 && m.frame_count() >= 3) {
    // Before the calibration frames are judged: their step speeds are per second.
    try {
      const motion::RateCheck rate = motion::rate_from_flights(m);
      if (rate.fps != m.fps) {
        notes.push_back(prefix + "fps auto: " + rate.evidence + "; read at " + fmt("%g", rate.fps) +
                        " fps (fps 0 keeps the file's)");
        m.fps = rate.fps;
      } else {
        notes.push_back(prefix + "fps auto: " + rate.evidence);
      }
    } catch (const std::invalid_argument& e) {  // no foot points to tell flights by
      notes.push_back(prefix + "fps auto: the file's " + fmt("%g", m.fps) +
                      " fps kept, unchecked: " + e.what());
    }
  }

  // Calibration frames, judged on the clip in metres at its rate.
  if (options.trim == "auto") {
    const motion::CalibrationCut cut = motion::detect_calibration_frames(m);
    if (cut.frames > 0) {
      keep_frames(m, cut.frames, m.frame_count() - 1);
      notes.push_back(prefix + "trim auto: " + cut.evidence + "; dropped (trim: none keeps them), " +
                      std::to_string(m.frame_count()) + " frames left");
    } else {
      notes.push_back(prefix + "trim auto: " + cut.evidence);
    }
  } else if (options.trim != "none") {
    const int frames = m.frame_count();
    const FrameRange r = trim_range(options.trim, frames);
    keep_frames(m, r.first, r.last);
    notes.push_back(prefix + "trim " + options.trim + ": frames " + std::to_string(r.first) + ".." +
                    std::to_string(r.last) + " kept of 0.." + std::to_string(frames - 1));
  }
  return notes;
}

}  // namespace kg::io
