#include "kg/motion/skeleton.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
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

// `name_taken`: whether another joint already has joint.name.
void check_joint(const Joint& joint, int joint_count, bool name_taken) {
  const std::string who = "joint '" + joint.name + "'";
  if (joint.name.empty())
    throw std::invalid_argument("joint " + std::to_string(joint_count) + " has no name");
  if (joint.parent < -1 || joint.parent >= joint_count)
    throw std::invalid_argument(who + ": parent " + std::to_string(joint.parent) +
                                " does not exist (expected -1 or 0.." + std::to_string(joint_count - 1) +
                                ")");
  if (name_taken) throw std::invalid_argument(who + ": duplicate joint name");
  if (!joint.offset.allFinite())
    throw std::invalid_argument(who + ": offset " + fmt_vector(joint.offset) + " is not finite");
  if (!joint.axis.allFinite() ||
      !(joint.axis * joint.axis.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
      !(joint.axis.determinant() > 0))
    throw std::invalid_argument(who + ": axis is not a rotation matrix");
  for (const Eigen::Vector3d& e : joint.end_sites)
    if (!e.allFinite()) throw std::invalid_argument(who + ": end site " + fmt_vector(e) + " is not finite");

  std::array<bool, 3> has_position{false, false, false};
  for (const Channel& c : joint.channels) {
    if (static_cast<int>(c.kind) > static_cast<int>(ChannelKind::Zrotation))
      throw std::invalid_argument(who + ": invalid channel kind " + std::to_string(static_cast<int>(c.kind)));
    if (std::isnan(c.min) || std::isnan(c.max) || c.min > c.max)
      throw std::invalid_argument(who + ": channel " + to_string(c.kind) + " has limits [" +
                                  std::to_string(c.min) + ", " + std::to_string(c.max) +
                                  "] (expected min <= max)");
    if (!is_rotation(c.kind)) {
      bool& seen = has_position[static_cast<std::size_t>(axis_index(c.kind))];
      if (seen) throw std::invalid_argument(who + ": channel " + to_string(c.kind) + " appears twice");
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

int Skeleton::add_joint(Joint joint) {
  check_joint(joint, joint_count(), index_.contains(joint.name));
  const int index = joint_count();
  joint.first_channel = channel_count_;
  const int channels = static_cast<int>(joint.channels.size());
  joints_.push_back(std::move(joint));
  try {
    index_.emplace(joints_.back().name, index);
  } catch (...) {  // out of memory: leave the skeleton as it was
    joints_.pop_back();
    throw;
  }
  channel_count_ += channels;
  return index;
}

int Skeleton::find_joint(const std::string& name) const {
  const auto it = index_.find(name);
  return it == index_.end() ? -1 : it->second;
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
  std::vector<Eigen::Vector3d> origin(joints_.size());  // file coordinates, rest pose
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto extend = [&](const Eigen::Vector3d& p_file) {
    const double y = file_to_world.row(1).dot(p_file);
    lo = std::min(lo, y);
    hi = std::max(hi, y);
  };
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const Joint& jt = joints_[j];
    origin[j] =
        (jt.parent >= 0 ? origin[static_cast<std::size_t>(jt.parent)] : Eigen::Vector3d::Zero()) + jt.offset;
    extend(origin[j]);
    for (const Eigen::Vector3d& e : jt.end_sites) extend(origin[j] + e);
  }
  return hi - lo;
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
