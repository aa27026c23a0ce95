// Contacts of a clip with the world (McCann et al. 2006 §3.2, fig. 3): polygonal areas fixed on
// segments (a foot's sole) whose vertices, while touching the floor, can each push with any force
// in a linearised friction cone. Per frame the touching vertices carry their world position and
// Jacobian, from which the generalised forces of the contact forces follow: N = Jᵀ P (eq. 9-11).
//
// Friction (fig. 3): the cone of Coulomb's law |f_t| <= μ f_n about the floor normal +Y is replaced
// by the pyramid spanned by four unit vectors per vertex, normalise(n ± μ t) for the tangents
// t = +X and +Z, whose edges lie on Coulomb's cone (inscribed: every force it allows is allowed by
// Coulomb's law). A force f at a vertex is P λ with λ >= 0 (4 entries, newtons).
//
// Detected feet (detect_contacts): per foot a rectangle of four vertices spanning heel to toe tip,
// built in the clip's flattest frame for that foot (where its ball and toe tip are both nearest
// their lowest heights: mid-stance). Not the rest pose: rest poses differ (CMU's ASF stands on flat
// feet, MotionBuilder's BVH of the same take points them at the floor). In that frame:
//   - A: the foot joint's origin (the ankle); T: the toe tip, the End Site of the foot's toe child
//     (else that child's origin), or without a toe child the foot's own End Site; the ball: the toe
//     child's origin (T without one);
//   - forward = the horizontal direction from A to T, d = the horizontal distance from A to T;
//   - the sole height is the lower of the ball and T;
//   - the heel lies heel_ratio * d behind A on the sole (default 0.25: the heel reaches a fifth of
//     the foot's length behind the ankle), so the foot's length is L = (1 + heel_ratio) d;
//   - the width is width_ratio * L (default 0.36: Winter's foot breadth 0.055 H over foot length
//     0.152 H, Biomechanics and Motor Control of Human Movement, 4th ed., fig. 4.1);
//   - vertices, in order around the sole: heel + w/2 side, tip + w/2 side, tip - w/2 side,
//     heel - w/2 side; the heel pair is fixed on the foot segment, the tip pair on the toe segment
//     (on the foot when it has no toe child), so toes bending at push-off carry the tip vertices.
// The heel pair touches while the heel point (heel centre) is planted, the tip pair while the toe
// tip is planted, as kg::motion::detect_footplants finds them (near the floor and slow); a foot
// touches while either pair does. A frame left without contact whose root is held up (a landing's
// impact, a takeoff's last push: support_acceleration) lets a pair near the floor touch however
// fast it moves.
//
//   Contacts c = detect_contacts(walk, {});
//   Eigen::MatrixXd N;
//   contact_generalised_forces(c.frames[f], c.channel_count(), body.friction, N);  // channels x 4 * points
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/footplants.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/motion.hpp"

namespace kg::retime {

// A point fixed on a segment.
struct ContactVertex {
  int joint = 0;                                    // skeleton joint index
  Eigen::Vector3d local = Eigen::Vector3d::Zero();  // metres, in the joint's frame
};

// A polygonal contact area: vertices in order around it (a single vertex is a point contact).
struct ContactPatch {
  std::string name;                       // unique within Contacts ("lfoot", a file's name)
  std::vector<ContactVertex> vertices{};  // >= 1
};

// One touching vertex at one frame.
struct ContactPoint {
  int patch = 0;                                    // index into Contacts::patches
  int vertex = 0;                                   // index into that patch's vertices
  Eigen::Vector3d world = Eigen::Vector3d::Zero();  // metres, world frame
  // d world / d channel values: 3 x channel_count (metres per metre or per radian), the same
  // generalised coordinates as the dynamics (kg::motion::point_jacobian).
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian{};
};

// The contact state of one frame.
struct ContactFrame {
  std::vector<ContactPoint> points{};  // touching vertices, by patch then vertex (may be empty: flight)

  bool touching(int patch) const;
  std::vector<int> patches() const;  // patches with a touching vertex, increasing
};

struct Contacts {
  std::shared_ptr<const motion::Skeleton> skeleton;  // shared, immutable
  std::vector<ContactPatch> patches{};
  std::vector<ContactFrame> frames{};  // one per frame of the clip
  double fps = 30.0;                   // the clip's frame rate
  std::string source;                  // "detected" or the contact file's path
  std::vector<std::string> notes{};    // what detection chose (feet, floor), for people

  int frame_count() const { return static_cast<int>(frames.size()); }
  int channel_count() const { return skeleton ? skeleton->channel_count() : 0; }
};

// Contacts from per-frame vertex activity: active[f][k] says whether vertex k touches at frame f,
// k numbering the vertices of all patches in order (patch 0's, then patch 1's, ...). Computes the
// touching vertices' world positions and Jacobians with the clip's poses. Throws
// std::invalid_argument for sizes that disagree, a joint out of range, a patch without vertices or
// a duplicate patch name.
Contacts assemble_contacts(const motion::Motion& motion, std::vector<ContactPatch> patches,
                           const std::vector<std::vector<bool>>& active);

// ---- detected feet --------------------------------------------------------------------------

struct FootContactOptions {
  // Foot joints by name (the ankle's segment: "lfoot", "LeftFoot"); empty: the feet
  // kg::motion::detect_footplants finds by common names.
  std::vector<std::string> feet{};
  double heel_ratio = 0.25;   // heel behind the ankle, as a fraction of the ankle-to-tip distance (>= 0)
  double width_ratio = 0.36;  // foot width as a fraction of the foot's length (> 0)
  // Frames the plants leave without contact while the root is held up (its vertical acceleration,
  // by second differences over about 1/30 s, above −9.81 + support_acceleration m/s²: the clip is
  // taken as captured under Earth's gravity), from a plant outwards: there a foot point within the
  // plants' leave height (height_threshold × hysteresis above its rest level) touches however fast
  // it moves, so the frames of a landing's impact and of a takeoff's last push, where feet still
  // strike or slide, are not taken for flight. 0: off (>= 0, m/s²).
  double support_acceleration = 4.9;
  // Plant detection of the heel and toe-tip points (its `points` are ignored: set from the feet).
  // A foot bears weight while it rolls, so contacts keep a plant's rolling ends (trim_distance 0)
  // and admit faster points than footplants do (0.3 m/s: a heel strikes at a few dm/s; at 0.15 m/s
  // CMU 16_15 loses half its double supports). A given floor (plants.floor) is where the heel and
  // tip points rest (rest_on_floor).
  motion::FootplantOptions plants = [] {
    motion::FootplantOptions o;
    o.rest_on_floor = true;
    o.trim_distance = 0.0;
    o.speed_threshold = 0.3;
    return o;
  }();
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// The rectangle of a foot (see the header comment) built in `pose` (skeleton.channel_count()
// values): vertices 0 and 3 are the heel pair, 1 and 2 the tip pair. `heel` and `tip` receive the
// heel centre (on the foot joint) and the toe tip (on the tip joint) the detection watches. Throws
// std::invalid_argument for a joint out of range, options out of range, or a foot whose tip is not
// ahead of its ankle horizontally in that pose.
ContactPatch foot_patch(const motion::Skeleton& skeleton, motion::FrameRef pose, int foot_joint,
                        const FootContactOptions& options, ContactVertex* heel = nullptr,
                        ContactVertex* tip = nullptr);

// The frame where the foot's ball and toe tip are both nearest their lowest heights over the clip
// (5th percentiles): max(ball − its low, tip − its low) is least. 0 for an empty clip.
int flattest_frame(const motion::Motion& motion, int foot_joint);

// Feet found and planted frames detected; throws std::invalid_argument for an unknown foot name
// (with the nearest name), no foot found, or options out of range.
Contacts detect_contacts(const motion::Motion& motion, const FootContactOptions& options);

// ---- contact files ----------------------------------------------------------------------------
//
// Format (version 1). Lengths in metres, frames 0-based and inclusive, times in seconds (rounded
// to the clip's frames). Unknown keys are errors.
//
//   version: 1
//   doc: "the hand on the rail in 07_05"   # optional, for people
//   patches:
//     - name: right hand                   # optional; default the joint's name; unique
//       joint: rhand                       # the segment the polygon is fixed on
//       vertices: [[0, 0, 0.04], [0.03, 0, 0.04], [0.03, 0, -0.04]]   # joint frame, metres, >= 1
//       frames: [[0, 40], [100, 140]]      # when it touches: inclusive ranges, or one [first, last]
//       # times: [[0, 0.33], [0.8, 1.2]]   # or in seconds (exactly one of frames and times)
//
// Every vertex of a patch touches over its ranges. Errors name file:line:column and the dotted
// key path (patches[1].vertices[2]): an unknown joint with the nearest name, a range reversed or
// out of the clip, an unknown key with the nearest allowed one.
inline constexpr int kContactFormatVersion = 1;

// Throws kg::Error with file:line:column.
Contacts read_contacts_file(const std::string& path, const motion::Motion& motion);
Contacts read_contacts_string(const std::string& text, const std::string& file_name,
                              const motion::Motion& motion);

// ---- friction and generalised forces -------------------------------------------------------

// The four unit basis forces of the linearised cone (columns, world frame, floor normal +Y):
// normalise(+Y + μ X), normalise(+Y − μ X), normalise(+Y + μ Z), normalise(+Y − μ Z).
// Throws std::invalid_argument unless μ is finite and >= 0.
Eigen::Matrix<double, 3, 4> friction_basis(double mu);

// N = Jᵀ P for one frame: channel_count x (4 * points.size()), column 4 i + k the generalised
// force (N or N m per newton of λ) of basis force k at touching point i. `N` is resized (no
// allocation when it already has that size).
void contact_generalised_forces(const ContactFrame& frame, int channel_count, double mu, Eigen::MatrixXd& N);

}  // namespace kg::retime
