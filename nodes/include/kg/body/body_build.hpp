// Building the physical character of a skeleton (McCann et al. 2006 §3.1, §4): which table
// segment each joint carries, its bone, and from those every joint's mass, centre of mass and
// inertia, the torque limits, friction and gravity of a BodyModel (body_model.hpp).
//
//   BodySpec spec;                                             // de Leva male, 70 kg
//   BuiltBody b = build_body_model(motion.skeleton, spec);     // b.body, b.class_mass, b.notes
//   LoadedBodySpec f = load_body_yaml("heavy_thigh.yaml", spec);  // the file's keys over spec
//   BuiltBody heavy = build_body_model(motion.skeleton, f.spec);
//   Eigen::Vector3d com = body_com(heavy.body, motion.values.row(f));  // world, metres
//
// Classes. Each joint gets a SegmentClass from the first joint-name pattern (a regular expression
// in RE2 syntax, kg/base/pattern.hpp, matched against the WHOLE name, case-sensitive) that
// matches it: the spec's own patterns first, then default_class_patterns(), which know the CMU
// ASF/AMC and BVH names, MotionBuilder's, Daz's, iClone's CC_Base_*, Bandai's, GAMES-105's and
// Mixamo-style (synth::make_figure) names. A joint no pattern matches is massless, and a note
// says so. Clavicles and hip connectors (lclavicle, lCollar, Shoulder_L, lhipjoint, lButtock)
// are massless by default: both tables' trunks run to the shoulder and hip joints, so their
// mass is the trunk's, which the spine joints carry; helper joints (twist and share bones, eyes,
// jaw, tongue, off-body roots such as Bandai's joint_Root on the floor) are massless too.
//
// Bones. A joint's segment is the rigid body moving with its frame; its bone is a vector in the
// joint's frame (metres) from the joint's origin to:
//   1. the children whose class is the joint's distal successor (thigh -> shank -> foot,
//      upper_arm -> forearm -> hand, trunk -> head_neck); else
//   2. the children of the joint's own class; else
//   3. its End Sites; else
//   4. its other children,
// taking the first of these groups with a non-zero offset, the mean of its non-zero offsets
// when it has several (a hand to the middle of its fingers' bases, a CMU thorax to its neck,
// Daz's chest to its neck rather than a collar, Daz's hip to its abdomen); zero when nothing
// is non-zero. A child at the joint's own origin (closer than 0.1 mm) makes no bone, but a
// massless one is looked through: its children take its place, at their rest positions in the
// joint's frame. So CMU's root, whose children all start at its origin, takes the middle of the
// hips through its massless hipjoints (a pelvis, as MotionBuilder's root gets directly), and
// iClone's head the middle of its eyes and jaw through FacialBone. Daz's and iClone's heads
// have no End Site at the top: their bones reach the eyes only, so their head+neck CoM sits a
// few centimetres low (override its `com` to correct it).
//
// Masses, tables. Table segment c has mass f_c M (M the requested body mass; the limbs' f_c for
// each side). The joints of a class form its groups: for head_neck and trunk one group, every
// joint of the class; for a limb class the connected runs of the class (a joint and its parent
// of one class are in one run), which must be exactly two, left and right. A group's mass is
// shared among its joints by bone length. Every class must have its groups, each of non-zero
// total bone length, or std::invalid_argument names what is missing and shows the YAML that maps
// it. Masses are then rescaled by M / sum so the total is exactly M (tables sum to 100% only up
// to their rounding); overrides (below) apply after that, so they change the total.
// Centre of mass: the table's fraction of the bone from the joint. Inertia about the CoM, from
// the radii of gyration k (fractions) with L the group's total bone length and l the joint's:
//   longitudinal radius k_long L, about the bone;
//   sagittal radius² (k_sag² - k_long²/2) l² + (k_long²/2) L², about the axis across the bone
//     nearest the body's anteroposterior direction; transverse likewise with k_trans, about the
//     remaining (mediolateral) axis.
// For a group of one joint (l = L) these are the table's radii; for a split group the girth
// part (k_long²/2 L², a solid cylinder's R²/4) stays whole while the part from the length
// shrinks with l, so a trunk in three pieces keeps its torsional inertia and its pieces' moments
// about the trunk's CoM add up to the table's, as a uniform cylinder's do.
// Anatomical directions come from a reference pose (default: the rest pose, every rotation
// channel zero and position channels at their offsets): up is world +Y; the mediolateral axis
// is the line through the two thighs' first joints, else the two upper arms', else the file's
// X; the anteroposterior axis is across both. For a bone within 60 degrees of that axis (a foot)
// the mediolateral axis is projected instead. A rest pose that is not anatomical (iClone's bones
// all along +Y) can swap the sagittal and transverse radii: at most 22% apart (the hand),
// under 7% elsewhere.
//
// Masses, cylinders. Each joint of a class with a bone is a solid cylinder of water (1000 kg/m³)
// along its bone, of its class's radius (BodySpec::radii): mass rho pi r² l, CoM at the bone's
// middle, inertia m r²/2 about the bone and m (3 r² + l²)/12 across it. M > 0 rescales every
// mass and inertia by M / sum (a density); M = 0 keeps the volumes' own mass.
//
// Overrides (BodySpec::segments), after the masses, first matching pattern wins per joint:
// `radius` makes the segment a water cylinder of that radius along its bone (table models too);
// `mass` sets the mass (kg, > 0) keeping the shape (inertia scaled alike); `mass_scale`
// multiplies mass and inertia (McCann's Fig. 11: a thigh ten times heavier); `com` sets the CoM
// (metres, joint frame); `inertia` sets the inertia about the CoM (kg m², joint-frame axes;
// symmetric positive definite, each principal moment at most the sum of the other two). A
// massless-class joint cannot be given mass (map it to a class); `mass_scale` and `com` leave
// it massless. A zero-length one can be given mass only with an `inertia` (`radius` needs a
// bone).
//
// Torque limits (BodySpec::torque_limits, first matching pattern wins per joint): one value v
// bounds every rotation channel of the joint to [-v, v] N m (its position channels, Bandai's
// constant bone offsets, stay unlimited: they hold the skeleton together); a list gives one
// bound per channel in the joint's channel order (N m rotation, N position), `.inf` for
// unlimited. Unmatched actuated channels are unlimited. The floating base is unactuated, its
// bounds 0 and 0 whatever the patterns say: every channel of a root and of each joint whose
// parent is in the floating base and massless (Bandai's Hips under joint_Root on the floor,
// iClone's CC_Base_Hip under RL_BoneRoot); a pattern matching only such joints is an error.
//
// Body files (YAML, version 1; parse_body_yaml). Every key is optional but `version`; the keys
// given replace the spec passed in (the node's params), the rest keep it:
//   version: 1
//   table: de_leva_male        # dempster | zatsiorsky_male | zatsiorsky_female | de_leva_male |
//                              # de_leva_female | cylinders
//   mass: 70                   # kg, > 0; cylinders: 0 = the volumes' own mass
//   radii: {trunk: 0.13}       # cylinders: metres (> 0) per class; others keep their defaults
//   classes:                   # joint-name regex -> class (or massless), before the defaults
//     "Spine[0-9]+": trunk
//     "lEye|rEye": massless
//   segments:                  # joint-name regex -> override (keys: mass, mass_scale, com,
//     lfemur: {mass_scale: 10} #   inertia, radius); com [x, y, z] m; inertia [Ixx, Iyy, Izz]
//     "[lr]hand": {mass: 0.5}  #   or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] kg m²
//   torque_limits:             # joint-name regex -> N m, one value or a list per channel
//     ".*": 400
//     "[lr]tibia": [250]
//   friction: 0.5              # Coulomb coefficient, >= 0
//   gravity: 9.81              # m/s² straight down (>= 0), or a world vector [x, y, z] (+Y up)
// Patterns are RE2 syntax (https://github.com/google/re2/wiki/Syntax: no backreferences or
// lookaround), at most Pattern::kMaxLength bytes.
// Unknown keys (reported by dotted path, with the nearest allowed name), duplicate keys, a
// wrong or missing version, non-numbers, non-finite numbers, masses and radii <= 0, bad regular
// expressions, unknown tables or classes, both mass and mass_scale, and (when building) patterns
// matching no joint and torque lists of the wrong length are errors naming file:line:column.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "kg/base/error.hpp"
#include "kg/body/anthropometry.hpp"
#include "kg/body/body_model.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::body {

// A joint-name pattern (RE2 regex, whole name) and the class it gives. `where` locates it
// in a body file for messages (empty when it comes from code).
struct ClassPattern {
  std::string pattern;
  SegmentClass segment_class = SegmentClass::Massless;
  kg::SourceLocation where{};
};

// The built-in patterns, tried after a spec's own (see the header comment for the families).
const std::vector<ClassPattern>& default_class_patterns();

struct SegmentOverride {
  std::string pattern;                       // joint-name regex, whole name
  std::optional<double> mass{};              // kg, > 0
  std::optional<double> mass_scale{};        // > 0 (not with mass)
  std::optional<Eigen::Vector3d> com{};      // metres, joint frame
  std::optional<Eigen::Matrix3d> inertia{};  // kg m² about the CoM, joint-frame axes
  std::optional<double> radius{};            // metres, > 0: a water cylinder along the bone
  kg::SourceLocation where{};
};

struct TorqueLimit {
  std::string pattern;         // joint-name regex, whole name
  std::vector<double> values;  // one (every rotation channel) or one per channel; > 0, +inf ok
  kg::SourceLocation where{};
};

struct BodySpec {
  BodyTable table = BodyTable::DeLevaMale;
  double mass = 70;  // kg: > 0 for a table; cylinders: 0 = the volumes' own mass, > 0 rescales
  std::array<double, kSegmentClassCount> radii = default_cylinder_radii();  // metres (cylinders)
  std::vector<ClassPattern> classes{};       // before default_class_patterns(); first match wins
  std::vector<SegmentOverride> segments{};   // first match wins per joint
  std::vector<TorqueLimit> torque_limits{};  // first match wins per joint
  double friction = 0.5;                     // >= 0
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};  // m/s², world (+Y up)
};

struct BuiltBody {
  BodyModel body;
  std::vector<SegmentClass> classes;                    // per joint, as matched
  std::vector<Eigen::Vector3d> bones;                   // per joint, joint frame, metres
  std::array<double, kSegmentClassCount> class_mass{};  // kg per class (both sides), overrides included
  std::vector<std::string> notes;  // for the user: massless joints, rescaling, what overrides did
};

// Classes by the rules above: `patterns` first, then the defaults. Throws kg::Error (at the
// pattern's `where`) for a bad regular expression.
std::vector<SegmentClass> classify_joints(const motion::Skeleton& skeleton,
                                          const std::vector<ClassPattern>& patterns = {});

// Every joint's bone (joint frame, metres) by the rules above.
std::vector<Eigen::Vector3d> segment_bones(const motion::Skeleton& skeleton,
                                           const std::vector<SegmentClass>& classes);

// The rest pose as frame values (channel_count()): rotation channels 0, position channels the
// matching offset components, so forward_kinematics draws the skeleton's offsets.
Eigen::RowVectorXd rest_pose_values(const motion::Skeleton& skeleton);

// The BodyModel of `skeleton` (kept, shared) under `spec`. `reference_pose` (channel_count()
// values) gives the anatomical directions; null: rest_pose_values. Throws std::invalid_argument
// for a bad spec or a skeleton missing required segments, kg::Error (located) for a pattern
// matching no joint, a bad regex or a torque list of the wrong length.
BuiltBody build_body_model(std::shared_ptr<const motion::Skeleton> skeleton, const BodySpec& spec,
                           const Eigen::RowVectorXd* reference_pose = nullptr);

// Whole-body centre of mass (world, metres) at one frame's values (channel_count()).
Eigen::Vector3d body_com(const BodyModel& body, motion::FrameRef frame);

// Throws std::invalid_argument, prefixed by `what`, unless I (kg m²) is finite, symmetric,
// positive definite and its largest principal moment at most the sum of the other two.
void check_segment_inertia(const Eigen::Matrix3d& I, const std::string& what);

// Throws std::invalid_argument naming the first problem: no skeleton, sizes other than one
// segment and class per joint and one bound per channel, a non-finite or negative number, an
// inertia of a massive segment not symmetric positive definite, torque_min > torque_max.
void check_body_model(const BodyModel& body, const std::string& who = "body model");

// What a body file gave: `spec` is the base with the file's keys applied; `given` the top-level
// keys the file set (version excluded), in file order.
struct LoadedBodySpec {
  BodySpec spec;
  std::vector<std::string> given;
};

// A body file's text (the format above); `path` names it in messages. Joint patterns are
// checked against a skeleton later, by build_body_model. Throws kg::Error.
LoadedBodySpec parse_body_yaml(std::string_view text, const std::string& path, const BodySpec& base = {});
// Reads `path` (kg::read_input_file) and parses it.
LoadedBodySpec load_body_yaml(const std::string& path, const BodySpec& base = {});

}  // namespace kg::body
