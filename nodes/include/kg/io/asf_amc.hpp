// Acclaim ASF (skeleton) and AMC (motion) files, as written by Vicon for the CMU database.
// Parsers are strict: anything malformed or truncated throws kg::Error whose what() is
// "file:line:column: expected ..., got ...". They never crash on bad input.
//
//   AsfSkeleton asf = read_asf("16.asf");                 // file lengths, radians
//   motion::Motion clip = read_amc("16_15.amc", asf);     // file lengths, radians, 120 fps
//   ImportedMotion m = import_asf_amc("16.asf", "16_15.amc", {.units = "auto"});  // metres
//
// How ASF maps onto skeleton.hpp's conventions (the CMU mocapPlayer's reading of the format):
//   - Every bone's rest frame is world-aligned. A bone's joint sits at its parent's tip, so its
//     offset is the PARENT's `direction * length` (children of the root: zero, i.e. at the root
//     position). The tip of a leaf bone (its own direction * length) becomes its End Site.
//   - The bone's `axis ax ay az ORDER` becomes Joint::axis C: the rotations about X, Y, Z by
//     ax, ay, az applied in ORDER (for XYZ: C = Rz(az) Ry(ay) Rx(ax)).
//   - Rotation dofs are applied in the order listed: for `dof rx ry rz` the motion's rotation
//     is R = Rz(rz) Ry(ry) Rx(rx) (mocapPlayer's glRotatef z, then y, then x), so the joint's
//     local rotation is C R C^T. Joint::channels compose in listed order, so they hold the
//     rotation dofs reversed (Zrotation, Yrotation, Xrotation) and the AMC values are permuted
//     while reading. The root's `order` and `axis`/`orientation` are read the same way.
//   - Root TX TY TZ become position channels replacing the root offset (`:root position`).
//     Translation dofs of other bones move the joint by C t from its rest offset; such a bone
//     gets three position channels holding offset + C t.
//   - The `l` (bone length) dof is refused: skeleton.hpp has no stretch channel.
//   - Limits become Channel::min/max (radians for rotations); `inf` and `-inf` are allowed.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"  // import_motion (a .bvh or an .amc by extension), long declared here
#include "kg/motion/motion.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::io {

// One degree of freedom as an ASF file names it (`dof rx ry` or the root's `order TX ...`).
enum class AsfDof : std::uint8_t { Tx, Ty, Tz, Rx, Ry, Rz };

// "tx", ..., "rz".
const char* to_string(AsfDof dof);

struct AsfBone {
  std::string name;  // "root" for the root
  int joint = -1;    // index in AsfSkeleton::skeleton
  int line = 0;      // line of the file where the bone begins (for messages)
  // The dofs in file order, which is the order of this bone's values on an AMC line.
  std::vector<AsfDof> dofs;
  // For each dof: the frame channel its value goes to (skeleton-wide index), except for the
  // translation dofs of a bone other than the root: the component (0, 1, 2) of its axis-frame
  // translation t (its three position channels hold offset + C t).
  std::vector<int> targets;
};

struct AsfSkeleton {
  // Lengths in the file's length unit, angles in radians, the file's axes (as BvhClip:
  // source_unit_metres 1, file_to_world identity); apply_import_options converts.
  std::shared_ptr<const motion::Skeleton> skeleton;
  std::vector<AsfBone> bones;  // bones[0] is the root, then the bones in skeleton joint order
  std::string path;            // as given to the reader, for messages
  std::string version;         // `:version`, "" when absent
  std::string name;            // `:name`, "" when absent
  std::string documentation;   // `:documentation` lines joined by '\n'
  double mass_unit = 1.0;      // `:units mass`
  // `:units length`: one file unit is (1 / length_unit) inches (CMU: 0.45). Absent: unset.
  std::optional<double> length_unit;
  bool degrees = true;  // `:units angle`: deg (the Acclaim default) or rad
  // Things the reader did that the user should know (e.g. limits it could not represent).
  std::vector<std::string> notes;

  // Metres per file length unit that :units declares (0.0254 / length_unit), if any.
  std::optional<double> declared_metres_per_unit() const;
  // nullptr when absent.
  const AsfBone* find_bone(std::string_view name) const;
};

// Parses ASF text; `path` only names the file in messages.
AsfSkeleton parse_asf(std::string_view text, const std::string& path);
// Reads and parses a file; a file that cannot be opened throws kg::Error naming it.
AsfSkeleton read_asf(const std::string& path);

// CMU's capture rate; AMC files carry none.
inline constexpr double kAmcDefaultFps = 120.0;

// Parses AMC text against its skeleton. The result has asf.skeleton, lengths in the ASF file's
// unit, radians, fps = kAmcDefaultFps and name = the stem of `path`. Every bone with dofs must
// appear exactly once per frame (in any order); frame numbers must count up by one. Angles are
// read as :DEGREES / :RADIANS says, else in the ASF's angle unit.
motion::Motion parse_amc(std::string_view text, const std::string& path, const AsfSkeleton& asf);
motion::Motion read_amc(const std::string& path, const AsfSkeleton& asf);

// read_asf + read_amc + apply_import_options (ImportedMotion: import_options.hpp; AMC files
// state no frame time, so file_frame_time is 0). options.units "auto" takes the ASF's :units;
// options.fps 0 means kAmcDefaultFps, said in the notes.
ImportedMotion import_asf_amc(const std::string& asf_path, const std::string& amc_path,
                              const ImportOptions& options);

// The ASF an AMC most likely belongs to: the CMU subject prefix of its name in the same folder
// ("dir/16_15.amc" -> "dir/16.asf"); "" when the name has no '_' or that file does not exist.
std::string guess_asf_for_amc(const std::string& amc_path);

}  // namespace kg::io
