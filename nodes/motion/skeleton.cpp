#include "kg/motion/skeleton.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>

#include "kg/base/error.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::motion {

namespace {

constexpr std::array<const char*, 6> kChannelNames = {"Xposition", "Yposition", "Zposition",
                                                      "Xrotation", "Yrotation", "Zrotation"};

bool equal_ignoring_case(const std::string& a, const char* b) {
  std::size_t i = 0;
  for (; i < a.size() && b[i] != '\0'; ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return i == a.size() && b[i] == '\0';
}

std::string fmt_vector(const Eigen::Vector3d& v) {
  return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + ")";
}

std::size_t name_hash(std::string_view name) {
  return std::hash<std::string_view>{}(name);
}
std::uint32_t name_tag(std::size_t hash) {
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(hash) >> 32);
}

// `name_taken`: whether another joint already has joint.name. The messages are built only when
// a check fails: this runs once per joint of every file read.
void check_joint(const Joint& joint, int joint_count, bool name_taken) {
  const auto who = [&] { return "joint '" + joint.name + "'"; };
  if (joint.name.empty())
    throw std::invalid_argument("joint " + std::to_string(joint_count) + " has no name");
  if (joint.parent < -1 || joint.parent >= joint_count)
    throw std::invalid_argument(who() + ": parent " + std::to_string(joint.parent) +
                                " does not exist (expected -1 or 0.." + std::to_string(joint_count - 1) +
                                ")");
  if (name_taken) throw std::invalid_argument(who() + ": duplicate joint name");
  if (!joint.offset.allFinite())
    throw std::invalid_argument(who() + ": offset " + fmt_vector(joint.offset) + " is not finite");
  // The identity (every joint but an ASF bone's) passes the rotation test; skip its arithmetic.
  if (joint.axis != Eigen::Matrix3d::Identity() &&
      (!joint.axis.allFinite() ||
       !(joint.axis * joint.axis.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
       !(joint.axis.determinant() > 0)))
    throw std::invalid_argument(who() + ": axis is not a rotation matrix");
  for (const Eigen::Vector3d& e : joint.end_sites)
    if (!e.allFinite()) throw std::invalid_argument(who() + ": end site " + fmt_vector(e) + " is not finite");

  std::array<bool, 3> has_position{false, false, false};
  for (const Channel& c : joint.channels) {
    if (static_cast<int>(c.kind) > static_cast<int>(ChannelKind::Zrotation))
      throw std::invalid_argument(who() + ": invalid channel kind " +
                                  std::to_string(static_cast<int>(c.kind)));
    if (std::isnan(c.min) || std::isnan(c.max) || c.min > c.max)
      throw std::invalid_argument(who() + ": channel " + to_string(c.kind) + " has limits [" +
                                  std::to_string(c.min) + ", " + std::to_string(c.max) +
                                  "] (expected min <= max)");
    if (!is_rotation(c.kind)) {
      bool& seen = has_position[static_cast<std::size_t>(axis_index(c.kind))];
      if (seen) throw std::invalid_argument(who() + ": channel " + to_string(c.kind) + " appears twice");
      seen = true;
    }
  }
  rotation_order(joint);  // throws for more than 3 rotations or neighbouring equal axes
}

}  // namespace

const char* to_string(ChannelKind k) {
  const auto i = static_cast<std::size_t>(k);
  return i < kChannelNames.size() ? kChannelNames[i] : "invalid";
}

std::optional<ChannelKind> channel_kind_from_string(const std::string& bvh_name) {
  for (std::size_t i = 0; i < kChannelNames.size(); ++i)
    if (equal_ignoring_case(bvh_name, kChannelNames[i])) return static_cast<ChannelKind>(i);
  return std::nullopt;
}

std::size_t Skeleton::index_slot(std::string_view name, std::size_t hash) const {
  const std::size_t mask = index_.size() - 1;
  const std::uint32_t tag = name_tag(hash);
  for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
    const IndexSlot& slot = index_[i];
    if (slot.joint < 0) return i;
    if (slot.tag == tag && joints_[static_cast<std::size_t>(slot.joint)].name == name) return i;
  }
}

void Skeleton::grow_index(std::size_t joints) {
  std::size_t size = 16;
  while (size < 2 * joints) size *= 2;
  if (size <= index_.size()) return;
  std::vector<IndexSlot> table(size);  // allocated before anything changes
  const std::size_t mask = size - 1;
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const std::size_t hash = name_hash(joints_[j].name);
    std::size_t i = hash & mask;
    while (table[i].joint >= 0) i = (i + 1) & mask;
    table[i] = {name_tag(hash), static_cast<std::int32_t>(j)};
  }
  index_ = std::move(table);
}

void Skeleton::reserve(int joints) {
  if (joints <= 0) return;
  joints_.reserve(static_cast<std::size_t>(joints));
  grow_index(static_cast<std::size_t>(joints));
}

int Skeleton::add_joint(Joint joint) {
  const std::size_t hash = name_hash(joint.name);
  check_joint(joint, joint_count(), !index_.empty() && index_[index_slot(joint.name, hash)].joint >= 0);
  const int index = joint_count();
  // Room first (the index for one more name, the joint vector by push_back): a bad_alloc leaves
  // the skeleton as it was.
  grow_index(joints_.size() + 1);
  const std::size_t slot = index_slot(joint.name, hash);
  joint.first_channel = channel_count_;
  const int channels = static_cast<int>(joint.channels.size());
  joints_.push_back(std::move(joint));
  index_[slot] = {name_tag(hash), index};
  channel_count_ += channels;
  return index;
}

int Skeleton::find_joint(std::string_view name) const {
  if (index_.empty()) return -1;
  return index_[index_slot(name, name_hash(name))].joint;
}

std::pair<int, int> Skeleton::channel_owner(int channel) const {
  if (channel < 0 || channel >= channel_count_)
    throw std::out_of_range("channel " + std::to_string(channel) + " out of range 0.." +
                            std::to_string(channel_count_ - 1));
  // first_channel increases with the joint index; a joint without channels shares its
  // first_channel with the next, so the last joint starting at or before `channel` owns it.
  auto it = std::upper_bound(joints_.begin(), joints_.end(), channel,
                             [](int c, const Joint& j) { return c < j.first_channel; });
  const int joint = static_cast<int>(it - joints_.begin()) - 1;
  return {joint, channel - joints_[static_cast<std::size_t>(joint)].first_channel};
}

std::string Skeleton::channel_name(int channel) const {
  const auto [j, c] = channel_owner(channel);
  const Joint& jt = joint(j);
  return jt.name + "." + to_string(jt.channels[static_cast<std::size_t>(c)].kind);
}

double Skeleton::rest_height() const {
  if (joints_.empty()) return 0.0;
  const std::vector<Eigen::Vector3d> origin = rest_origins();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto extend = [&](const Eigen::Vector3d& p_file) {
    const double y = file_to_world.row(1).dot(p_file);
    lo = std::min(lo, y);
    hi = std::max(hi, y);
  };
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    extend(origin[j]);
    for (const Eigen::Vector3d& e : joints_[j].end_sites) extend(origin[j] + e);
  }
  return hi - lo;
}

std::vector<Eigen::Vector3d> Skeleton::rest_world_origins() const {
  std::vector<Eigen::Vector3d> origin = rest_origins();
  for (Eigen::Vector3d& p : origin) p = file_to_world * p;
  return origin;
}

std::vector<Eigen::Vector3d> Skeleton::rest_origins() const {
  std::vector<Eigen::Vector3d> origin(joints_.size());
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const Joint& jt = joints_[j];
    origin[j] =
        (jt.parent >= 0 ? origin[static_cast<std::size_t>(jt.parent)] : Eigen::Vector3d::Zero()) + jt.offset;
  }
  return origin;
}

std::string nearest_joint_name(const Skeleton& sk, const std::string& name) {
  auto lower = [](std::string t) {
    for (char& ch : t) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return t;
  };
  const std::string want = lower(name);
  std::string prefix, contains;
  std::vector<std::string> names;
  for (const Joint& j : sk.joints()) {
    names.push_back(j.name);
    if (want.empty()) continue;
    const std::string n = lower(j.name);
    if (n.rfind(want, 0) == 0 && (prefix.empty() || j.name.size() < prefix.size())) prefix = j.name;
    if (n.find(want) != std::string::npos && (contains.empty() || j.name.size() < contains.size()))
      contains = j.name;
  }
  if (!prefix.empty()) return prefix;
  if (!contains.empty()) return contains;
  return kg::nearest_name(name, names);
}

}  // namespace kg::motion
