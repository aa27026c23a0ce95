// Skeleton maps (Gleicher 1998 §8): which feature points of a source character correspond to
// which of a target of another structure (a game rig, a creature, a robot), and how strongly.
//
//   SkeletonChains c = find_chains(skeleton);                 // pelvis, spine, neck, legs, arms
//   ProposedMap p = propose_map(source, target);              // chains of both, paired by role
//   write_skeleton_map(os, p.map);                            // the file the user edits
//   SkeletonMap m = read_skeleton_map("walk_to_g1.yaml", source, target);
//   std::vector<FeaturePair> pairs = feature_pairs(m);        // chains' pairs + the file's own
//
// Chains. A humanoid is described by its chains, each a role -> joint table:
//   pelvis: JOINT                      the joint the legs branch from
//   spine: [JOINT, ...]                from just above the pelvis to the chest (the joint the arms
//                                      branch from), in order; the last is the chest
//   neck: [JOINT, ...]                 from just above the chest to the head; the last is the head
//   left_leg / right_leg: {hip: J, knee: J, ankle: J, toe: J}         toe optional
//   left_arm / right_arm: {clavicle: J, shoulder: J, elbow: J, wrist: J}   clavicle optional
// Every chain is optional (a robot without a neck has none). A joint names a skeleton joint (for
// a URDF the joint carrying the link, fixed joints too) and is a point: its origin.
//
// Map files (read_skeleton_map; every error names file:line:column and, for an unknown joint,
// the nearest joint of that skeleton):
//   version: 1
//   source: {file: 07.asf, chains: {pelvis: root, spine: [lowerback, upperback, thorax], ...}}
//   target: {file: g1_29dof.urdf, chains: {pelvis: pelvis, left_leg: {hip: ..., ...}, ...}}
//   pairs:                             # optional: pairs of your own, or changes to the chains'
//     - name: left_heel                # unique; defaults to kind + the two joints
//       kind: position                 # position | direction | orientation
//       source: {joint: lfoot, offset: [0, -0.02, -0.05]}   # or just a joint name; metres,
//       target: left_ankle_roll_joint                       #   in the joint's frame
//       weight: 4                      # > 0 (default 1); or hard: true (an exact constraint)
//     - {kind: direction, source: {from: lhumerus, to: lradius}, target: {from: A, to: B}}
//     - {name: left_leg.ankle, weight: 10}   # a chain pair's name: changes its weight or hard
// `file` is what the map was made for (informative; the joints are checked against the
// skeletons it is used with).
//
// Pairs the chains give (feature_pairs), for each chain both sides have (names are
// CHAIN.FEATURE); positions are joint origins, directions from one joint's origin to another's:
//   pelvis.position (1), pelvis.orientation (1), spine.chest (orientation, 0.5),
//   spine.direction (pelvis -> chest, 1), neck.head (position, 1), neck.orientation (0.5),
//   LEG.knee (position, 1), LEG.ankle (position, 4), LEG.toe (position, 2; when both have a toe),
//   LEG.foot (orientation of Limb::foot, 1),
//   LEG.thigh (direction hip -> knee, 1), LEG.shin (direction knee -> ankle, 1),
//   ARM.elbow (position, 1), ARM.wrist (position, 2), ARM.upper_arm (direction shoulder ->
//   elbow, 1), ARM.forearm (direction elbow -> wrist, 1).
// Weights are relative (the solver's objective); a hard pair holds exactly.
//
// Rest poses. The two skeletons' rest poses may differ (a T-pose against an A-pose, joint frames
// pointing elsewhere): directions and positions are compared in the world, where that does not
// matter; an orientation pair compares the target joint's world rotation with the source's
// times the constant rotation that takes the source joint's rest frame to the target's
// (rest_offsets), so no quaternion is typed by hand. A rest pose is every rotation channel at
// zero and position channels at their offsets, file_to_world applied.
#pragma once

#include <array>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "kg/motion/skeleton.hpp"

namespace kg::retarget {

inline constexpr int kSkeletonMapVersion = 1;

// One leg or arm. Roles: leg {hip, knee, ankle, toe}, arm {clavicle, shoulder, elbow, wrist}; -1
// when absent (toe, clavicle). `path` is every joint from the limb's first joint below its branch
// point to its end, in order (for messages and the solver's per-chain scale).
struct Limb {
  int root = -1;    // clavicle (arm) or the leg's first joint, for the record; -1 when none
  int upper = -1;   // hip | shoulder
  int middle = -1;  // knee | elbow
  int lower = -1;   // ankle | wrist
  int end = -1;     // toe (legs; -1 when none); unused for arms
  // Legs: the joint carrying the foot segment, whose rotation is the foot's: the toe's parent
  // (a robot's ankle roll below its ankle pitch), the ankle when there is no toe. Derived, not a
  // role of map files; -1 for arms.
  int foot = -1;
  std::vector<int> path{};
  bool found() const { return upper >= 0 && middle >= 0 && lower >= 0; }
};

// A limb role: its name in map files, notes and pair names, where a Limb keeps its joint, and
// whether a map's limb must name it.
struct LimbRole {
  const char* name;
  int Limb::*joint;
  bool required;
};
inline constexpr std::array<LimbRole, 4> kLegRoles{{{"hip", &Limb::upper, true},
                                                    {"knee", &Limb::middle, true},
                                                    {"ankle", &Limb::lower, true},
                                                    {"toe", &Limb::end, false}}};
inline constexpr std::array<LimbRole, 4> kArmRoles{{{"clavicle", &Limb::root, false},
                                                    {"shoulder", &Limb::upper, true},
                                                    {"elbow", &Limb::middle, true},
                                                    {"wrist", &Limb::lower, true}}};
inline const std::array<LimbRole, 4>& limb_role_table(bool leg) {
  return leg ? kLegRoles : kArmRoles;
}

enum Side { kLeft = 0, kRight = 1 };

struct SkeletonChains {
  int pelvis = -1;
  std::vector<int> spine{};            // last = chest
  std::vector<int> neck{};             // last = head
  std::array<Limb, 2> legs{}, arms{};  // [kLeft], [kRight]
  // How each was decided, with its evidence (names, lengths, sides), one line each.
  std::vector<std::string> notes{};
  // Chains that could not be found, with why.
  std::vector<std::string> missing{};
};

// The chains of a humanoid skeleton, found from its structure:
//   - the legs are the pair of sibling subtrees of equal length (within 5%) and equal joint count
//     that reach furthest (offset plus longest path below), their parent the pelvis; the arms the
//     next such pair outside the legs, their parent the chest; the spine the tree path between
//     pelvis and chest; the neck the chest's remaining child that reaches furthest, down to the
//     head (the joint named head on that path, else the path's last joint with rotation channels);
//   - a limb is followed from its first joint through the child that reaches furthest. Its
//     middle joint (knee, elbow) is the first joint named for it (knee|shin|calf|tibia|lowerleg|
//     leg; elbow|forearm|radius|lowerarm), else the joint between the two adjacent non-zero
//     segments whose shorter one is longest (thigh and shin, upper arm and forearm; said so).
//     The upper joint is the first of the run of joints before the middle one named thigh|femur|
//     upleg|upperleg (else hip) or upperarm|humerus|shldr|arm (else shoulder), skipping joints
//     without channels or at their parent's origin; else the joint starting the segment into
//     the middle joint. The lower joint is the first after the middle one named ankle|foot or
//     wrist|hand, else the end of the segment out of it. A leg's toe is the first joint after
//     the ankle named toe|ball, else the next joint on the path. Names are matched
//     case-insensitively with the side marker removed.
//   - left and right: from the names of the two limbs when they differ by a side marker (l/r,
//     left/right), else from the rest pose: the character faces where its toes point, and its
//     left is up x forward.
// What cannot be found goes to `missing`; nothing throws for a skeleton that is not humanoid.
SkeletonChains find_chains(const motion::Skeleton& skeleton);

enum class FeatureKind { Position, Direction, Orientation };
const char* to_string(FeatureKind kind);

// One side of a feature pair: a point (joint + offset), for directions a second point too.
struct FeatureSide {
  motion::PointRef point{};  // character unused (0)
  motion::PointRef to{};     // direction: the point it points to; joint -1 otherwise
};

struct FeaturePair {
  std::string name;
  FeatureKind kind = FeatureKind::Position;
  FeatureSide source{}, target{};
  double weight = 1.0;  // > 0
  bool hard = false;
};

// The chains as written in a map file: role -> joint index; one per side.
struct SkeletonMapSide {
  std::string file{};  // what the map was made for (informative)
  SkeletonChains chains{};
};

struct SkeletonMap {
  std::string path{};  // the file it was read from ("" when built)
  SkeletonMapSide source{}, target{};
  std::vector<FeaturePair> pairs{};  // the file's own pairs (feature_pairs adds the chains')
  // Changes to chain pairs by name (`{name: left_leg.ankle, weight: 10}`): weight <= 0 keeps it.
  struct Change {
    std::string name;
    double weight = 0;
    int hard = -1;  // -1 unchanged, 0 soft, 1 hard
  };
  std::vector<Change> changes{};
};

// The chains' pairs (above), then the map's own, with `changes` applied. Throws
// std::invalid_argument naming a change that names no chain pair.
std::vector<FeaturePair> feature_pairs(const SkeletonMap& map);

// Reads a map file against the two skeletons it will be used with. Throws kg::Error at
// file:line:column for malformed YAML, unknown keys, an unknown joint (with the nearest joint of
// that skeleton), a bad kind, weight or offset, a duplicate pair name, a change naming no chain
// pair. `text` overload: `path` names the file in messages.
SkeletonMap parse_skeleton_map(std::string_view text, const std::string& path, const motion::Skeleton& source,
                               const motion::Skeleton& target);
SkeletonMap read_skeleton_map(const std::string& path, const motion::Skeleton& source,
                              const motion::Skeleton& target);

// The map as a file read_skeleton_map reads back to the same map.
void write_skeleton_map(std::ostream& os, const SkeletonMap& map, const motion::Skeleton& source,
                        const motion::Skeleton& target);

// A chains-only file (a preset: `version: 1`, optional `doc`, `chains: {...}`), as in a map
// side. Throws kg::Error as read_skeleton_map.
SkeletonChains parse_chains_preset(std::string_view text, const std::string& path,
                                   const motion::Skeleton& skeleton);

// A proposed map: both skeletons' chains, and what matched.
struct ProposedMap {
  SkeletonMap map;
  std::vector<std::string> matched;  // "left_leg: lfemur, ltibia, lfoot, ltoes -> left_hip_pitch_joint, ..."
  std::vector<std::string> unmatched;  // "neck: the target has none (no child of the chest ...)"
  std::vector<std::string> notes;      // both sides' find_chains notes, prefixed source:/target:
};
// find_chains on both, paired by chain.
ProposedMap propose_map(const motion::Skeleton& source, const motion::Skeleton& target,
                        const std::string& source_file = "", const std::string& target_file = "");

// The child of `joint` whose subtree reaches furthest from `joint`'s origin in the rest pose
// (its offset plus the longest path below it, End Sites included; the first on a tie), -1 for a
// leaf. The rule find_chains follows a limb by, and rest_offsets a limb joint's axis by.
int furthest_child(const motion::Skeleton& skeleton, int joint);

// The body's frame in the rest pose (world): columns left (left hip minus right hip from the
// chains' legs, else left shoulder minus right shoulder, made horizontal), up (world +Y), and
// forward (left x up). `side` names the skeleton in the message when the chains give no left
// (std::invalid_argument).
Eigen::Matrix3d body_frame(const SkeletonChains& chains, const motion::Skeleton& skeleton,
                           const std::string& side);

// For each pair (same order), the constant rotation R with target_world ≈ source_world * R for
// an orientation pair (identity for other kinds). Each side's joint gets an anatomical frame in
// its rest pose: its first axis the body's left (left hip minus right hip from the map's legs,
// else left shoulder minus right shoulder, made horizontal), its second the joint's own axis
// (world up for the pelvis, spine and neck; for a limb joint the direction to its child reaching
// furthest), the third across both; A is that frame in the joint's frame, and R = A_s A_t^T, so
// the two anatomical frames coincide in the world. Throws std::invalid_argument when the map
// gives no left (no legs or arms on a side) and a pair needs it.
std::vector<Eigen::Matrix3d> rest_offsets(const SkeletonMap& map, const std::vector<FeaturePair>& pairs,
                                          const motion::Skeleton& source, const motion::Skeleton& target);

}  // namespace kg::retarget
