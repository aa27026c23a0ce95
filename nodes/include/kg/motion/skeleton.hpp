// An articulated figure: a forest of joints (usually one root), each with a rest offset from its
// parent, an optional fixed axis frame, and its channels (degrees of freedom) in any order.
//
// Conventions (every importer converts to these; exporters convert back):
//   - lengths in metres, angles in radians;
//   - a joint's local transform is
//       T(offset, with position channels replacing the matching offset component)
//       * axis * R(c0) * R(c1) * ... * axis^T
//     where c0, c1, ... are its rotation channels in the order listed (BVH's convention: the
//     first listed rotation is the outermost), and `axis` is identity except for ASF bones;
//   - world = file_to_world * (chain of local transforms). file_to_world is a rotation that
//     makes +Y up in the world (identity for Y-up files); exporters write file coordinates.
//
//   Skeleton s;
//   int hip = s.add_joint({.name = "hip", .parent = -1, .channels = {Channel::Xposition, ...}});
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

namespace kg::motion {

enum class ChannelKind : std::uint8_t { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

inline bool is_rotation(ChannelKind k) {
  return k >= ChannelKind::Xrotation;
}
// 0, 1, 2 for X, Y, Z.
inline int axis_index(ChannelKind k) {
  return static_cast<int>(k) % 3;
}
// "Xposition", ..., "Zrotation" (BVH names).
const char* to_string(ChannelKind k);
std::optional<ChannelKind> channel_kind_from_string(const std::string& bvh_name);

struct Channel {
  ChannelKind kind = ChannelKind::Xrotation;
  // Joint limits, in the channel's unit (metres or radians); infinite when unlimited.
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

struct Joint {
  std::string name;
  int parent = -1;                                     // index of the parent joint, -1 for a root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();    // metres, in the parent's frame
  Eigen::Matrix3d axis = Eigen::Matrix3d::Identity();  // ASF `axis`: the frame channels rotate in
  std::vector<Channel> channels{};
  int first_channel = 0;  // index of channels[0] in a frame's values
  // Tips: BVH "End Site" offsets (metres, this joint's frame). Usually zero or one.
  std::vector<Eigen::Vector3d> end_sites{};
};

class Skeleton {
 public:
  // Appends a joint; its parent must already exist. Sets first_channel. Returns its index.
  // Throws std::invalid_argument on a bad parent or a duplicate name. Constant time on average
  // (names are kept in a hash index), so building a skeleton is linear in its joints. On a throw
  // the skeleton is left as it was.
  int add_joint(Joint joint);
  // Room for `joints` joints in all, so that adding that many moves no joint and regrows no
  // index; a hint for readers that know (or can bound) the count up front.
  void reserve(int joints);

  const std::vector<Joint>& joints() const { return joints_; }
  const Joint& joint(int index) const { return joints_[static_cast<std::size_t>(index)]; }
  // For editing offsets, axes, limits and end sites; a joint's name is indexed by add_joint and
  // must not be changed through this.
  Joint& joint_mut(int index) { return joints_[static_cast<std::size_t>(index)]; }
  int joint_count() const { return static_cast<int>(joints_.size()); }
  int channel_count() const { return channel_count_; }
  // -1 when absent. Constant time on average.
  int find_joint(std::string_view name) const;
  // The joint owning frame channel `channel`, and that channel's index within the joint.
  std::pair<int, int> channel_owner(int channel) const;
  // "hip.Xrotation".
  std::string channel_name(int channel) const;

  // Rotation taking file coordinates to world coordinates (+Y up); see above.
  Eigen::Matrix3d file_to_world = Eigen::Matrix3d::Identity();
  // Metres per unit of the file it came from (0.01 for cm); exporters write back in that unit.
  double source_unit_metres = 1.0;

  // Every joint's origin in the rest pose (every rotation channel zero, the root at the origin),
  // file coordinates (apply file_to_world for world), metres; one per joint.
  std::vector<Eigen::Vector3d> rest_origins() const;
  // The same in world coordinates (file_to_world applied).
  std::vector<Eigen::Vector3d> rest_world_origins() const;

  // Standing height estimate: vertical extent (world Y) of joints and end sites in the rest
  // pose, metres.
  double rest_height() const;

 private:
  // The name index: open addressing with linear probing over a power-of-two table at most half
  // full, one flat array (no allocation per joint, unlike a node-based map). A slot holds the
  // upper bits of its name's hash (compared before the name) and the joint's index, -1 if empty.
  struct IndexSlot {
    std::uint32_t tag = 0;
    std::int32_t joint = -1;
  };
  // The slot holding `name` (hash `hash`), else the empty slot where it would go; the table must
  // not be empty.
  std::size_t index_slot(std::string_view name, std::size_t hash) const;
  // Makes the table room for `joints` names at most half full (rehashing what it holds).
  void grow_index(std::size_t joints);

  std::vector<Joint> joints_;
  std::vector<IndexSlot> index_;
  int channel_count_ = 0;
};

// A point fixed on a segment: `local` in `joint`'s frame (metres) of character `character`
// (0 for the only or first character, 1 for the second of a two-character problem).
struct PointRef {
  int character = 0;
  int joint = -1;
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
};

// The joint name of `skeleton` nearest to a misspelt `name`, for messages: the shortest name
// starting with it (case-insensitive: "LeftToe" -> "LeftToeBase"), else the shortest containing
// it, else the nearest by edit distance; "" when none is close.
std::string nearest_joint_name(const Skeleton& skeleton, const std::string& name);

}  // namespace kg::motion
