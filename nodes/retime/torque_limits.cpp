// Torque limits observed in the source motion (torque_limits.hpp): each clip's unlimited hulls give
// the contact forces, the peaks of |τ| the limits.
#include "kg/retime/torque_limits.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/base/text.hpp"
#include "kg/body/body_build.hpp"

namespace kg::retime {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string clip_name(const ClipLoads& c, std::size_t index) {
  return c.name.empty() ? "clip " + std::to_string(index) : "clip '" + c.name + "'";
}

// Channels of joints without a parent: the hulls' equality rows, whatever the body says.
std::vector<bool> root_channels(const motion::Skeleton& s) {
  std::vector<bool> root(static_cast<std::size_t>(s.channel_count()), false);
  for (const motion::Joint& j : s.joints())
    if (j.parent < 0)
      for (std::size_t i = 0; i < j.channels.size(); ++i)
        root[static_cast<std::size_t>(j.first_channel) + i] = true;
  return root;
}

// Channels whose limits are estimated: actuated (not a root's, not bounded to [0, 0]) and, unless
// asked, not a position channel.
std::vector<bool> estimated_channels(const body::BodyModel& body, bool position_channels) {
  const motion::Skeleton& s = *body.skeleton;
  std::vector<bool> out = root_channels(s);
  out.flip();
  for (int c = 0; c < s.channel_count(); ++c) {
    const auto [joint, k] = s.channel_owner(c);
    const bool position = !motion::is_rotation(s.joint(joint).channels[static_cast<std::size_t>(k)].kind);
    if ((body.torque_min[c] == 0 && body.torque_max[c] == 0) || (position && !position_channels))
      out[static_cast<std::size_t>(c)] = false;
  }
  return out;
}

// Every name `name` mirrors to by one rule (torque_limits.hpp); may contain duplicates.
std::vector<std::string> mirror_names(const std::string& name) {
  std::vector<std::string> out;
  if (name.size() >= 2) {
    static constexpr std::pair<char, char> kSwap[] = {{'l', 'r'}, {'r', 'l'}, {'L', 'R'}, {'R', 'L'}};
    for (const auto& [from, to] : kSwap)
      if (name[0] == from) out.push_back(to + name.substr(1));
  }
  // Left <-> Right in every case spelling, all occurrences at once.
  static constexpr std::pair<const char*, const char*> kWords[] = {
      {"Left", "Right"}, {"left", "right"}, {"LEFT", "RIGHT"}};
  for (const auto& [left, right] : kWords) {
    std::string swapped;
    bool changed = false;
    for (std::size_t i = 0; i < name.size();) {
      const std::string_view rest = std::string_view(name).substr(i);
      if (rest.starts_with(left)) {
        swapped += right, i += std::string_view(left).size(), changed = true;
      } else if (rest.starts_with(right)) {
        swapped += left, i += std::string_view(right).size(), changed = true;
      } else {
        swapped += name[i++];
      }
    }
    if (changed) out.push_back(std::move(swapped));
  }
  // Whole one-letter tokens between separators.
  auto separator = [](char c) { return c == '_' || c == '.' || c == '-' || c == ' '; };
  std::string swapped = name;
  bool changed = false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const bool alone = (i == 0 || separator(name[i - 1])) && (i + 1 == name.size() || separator(name[i + 1]));
    if (!alone) continue;
    const char c = name[i];
    const char m = c == 'l' ? 'r' : c == 'r' ? 'l' : c == 'L' ? 'R' : c == 'R' ? 'L' : c;
    if (m != c) swapped[i] = m, changed = true;
  }
  if (changed) out.push_back(std::move(swapped));
  return out;
}

bool same_channel_kinds(const motion::Joint& a, const motion::Joint& b) {
  if (a.channels.size() != b.channels.size()) return false;
  for (std::size_t i = 0; i < a.channels.size(); ++i)
    if (a.channels[i].kind != b.channels[i].kind) return false;
  return true;
}

void check_clip(const body::BodyModel& body, const ClipLoads& clip, std::size_t index) {
  const std::string who = "torque limits: " + clip_name(clip, index);
  const int channels = body.skeleton->channel_count();
  if (clip.contacts == nullptr) throw std::invalid_argument(who + " has no contacts");
  if (clip.contacts->frame_count() != static_cast<int>(clip.torques.size()))
    throw std::invalid_argument(who + " has " + std::to_string(clip.contacts->frame_count()) +
                                " contact frames but " + std::to_string(clip.torques.size()) +
                                " frames of torque coefficients");
  if (clip.contacts->skeleton && clip.contacts->channel_count() != channels)
    throw std::invalid_argument(who + ": its contacts' skeleton has " +
                                std::to_string(clip.contacts->channel_count()) + " channels, the body " +
                                std::to_string(channels));
  for (std::size_t f = 0; f < clip.torques.size(); ++f) {
    const FrameTorques& t = clip.torques[f];
    if (t.velocity.size() != channels || t.acceleration.size() != channels || t.gravity.rows() != channels)
      throw std::invalid_argument(
          who + " frame " + std::to_string(f) + ": torque coefficients of " +
          std::to_string(t.velocity.size()) + ", " + std::to_string(t.acceleration.size()) + " and " +
          std::to_string(t.gravity.rows()) + " channels, the body has " + std::to_string(channels));
    if (!t.velocity.allFinite() || !t.acceleration.allFinite() || !t.gravity.allFinite())
      throw std::invalid_argument(who + " frame " + std::to_string(f) + ": torque coefficients not finite");
  }
}

}  // namespace

const char* to_string(FrameUse use) {
  switch (use) {
    case FrameUse::Original:
      return "original";
    case FrameUse::Nearest:
      return "nearest";
    case FrameUse::Flight:
      return "flight";
    case FrameUse::LeastSquares:
      return "least-squares";
    case FrameUse::Skipped:
      return "skipped";
  }
  return "?";
}

int TorqueLimitEstimate::count(FrameUse use) const {
  int n = 0;
  for (const std::vector<ObservedFrame>& clip : frames)
    n += static_cast<int>(
        std::count_if(clip.begin(), clip.end(), [&](const ObservedFrame& f) { return f.use == use; }));
  return n;
}

std::vector<std::pair<int, int>> mirrored_joints(const motion::Skeleton& s) {
  std::vector<std::pair<int, int>> pairs;
  std::vector<bool> paired(static_cast<std::size_t>(s.joint_count()), false);
  for (int i = 0; i < s.joint_count(); ++i) {
    if (paired[static_cast<std::size_t>(i)]) continue;
    for (const std::string& name : mirror_names(s.joint(i).name)) {
      const int j = s.find_joint(name);
      if (j < 0 || j == i || paired[static_cast<std::size_t>(j)] ||
          !same_channel_kinds(s.joint(i), s.joint(j)))
        continue;
      pairs.emplace_back(i, j);
      paired[static_cast<std::size_t>(i)] = paired[static_cast<std::size_t>(j)] = true;
      break;
    }
  }
  return pairs;
}

body::BodyModel without_torque_limits(const body::BodyModel& body, bool position_channels) {
  body::check_body_model(body, "torque limits");
  body::BodyModel out = body;
  const std::vector<bool> estimated = estimated_channels(body, position_channels);
  for (std::size_t c = 0; c < estimated.size(); ++c)
    if (estimated[c]) {
      out.torque_min[static_cast<Eigen::Index>(c)] = -kInf;
      out.torque_max[static_cast<Eigen::Index>(c)] = kInf;
    }
  return out;
}

void TorqueLimitOptions::validate() const {
  using options::require;
  const char* o = "TorqueLimitOptions";
  require(options::positive(margin), o, "margin", margin,
          "> 0 and finite (limits = margin x the observed peak; >= 1 keeps the clips' own timing feasible)");
  require(options::non_negative(floor), o, "floor", floor, ">= 0 and finite (N m)");
  hulls.validate();
}

TorqueLimitEstimate estimate_torque_limits(const body::BodyModel& body, std::span<const ClipLoads> clips,
                                           const TorqueLimitOptions& options) {
  options.validate();
  body::check_body_model(body, "torque limits");
  if (clips.empty()) throw std::invalid_argument("torque limits: no clip to observe");
  for (std::size_t i = 0; i < clips.size(); ++i) check_clip(body, clips[i], i);

  const motion::Skeleton& s = *body.skeleton;
  const int channels = s.channel_count();
  const body::BodyModel unlimited = without_torque_limits(body, options.position_channels);
  TorqueLimitEstimate out;
  out.estimated = estimated_channels(body, options.position_channels);
  out.peak = Eigen::VectorXd::Zero(channels);
  out.peak_clip.assign(static_cast<std::size_t>(channels), -1);
  out.peak_frame.assign(static_cast<std::size_t>(channels), -1);
  out.frames.resize(clips.size());

  Eigen::VectorXd tau(channels);
  for (std::size_t ci = 0; ci < clips.size(); ++ci) {
    const ClipLoads& clip = clips[ci];
    const Hulls hulls = build_hulls(unlimited, *clip.contacts, clip.torques, options.hulls);
    std::vector<ObservedFrame>& observed = out.frames[ci];
    observed.resize(hulls.frames.size());
    for (std::size_t f = 0; f < hulls.frames.size(); ++f) {
      const FrameHull& h = hulls.frames[f];
      ObservedFrame& o = observed[f];
      const Eigen::VectorXd* lambda = &h.centre_lambda;
      switch (h.status) {
        case HullStatus::Feasible:
          o.use = h.centre_is_original ? FrameUse::Original : FrameUse::Nearest;
          o.timing = h.centre_is_original ? Eigen::Vector2d(0, 1) : h.centre;
          break;
        case HullStatus::Flight:
          o.use = FrameUse::Flight;
          o.timing = {0, 1};
          lambda = nullptr;
          break;
        case HullStatus::Infeasible:
          o.use = options.infeasible == InfeasibleFrames::Skip ? FrameUse::Skipped : FrameUse::LeastSquares;
          o.timing = o.use == FrameUse::Skipped ? Eigen::Vector2d(0, 1) : h.centre;
          break;
      }
      if (o.use == FrameUse::Skipped) continue;
      const FrameTorques& t = clip.torques[f];
      tau.noalias() = t.velocity * o.timing.y();
      tau.noalias() += t.acceleration * o.timing.x();
      tau.noalias() += t.gravity * body.gravity;
      if (lambda != nullptr && h.N.cols() > 0) tau.noalias() -= h.N * *lambda;
      for (int c = 0; c < channels; ++c) {
        const double a = std::abs(tau[c]);
        if (!out.estimated[static_cast<std::size_t>(c)] || a <= out.peak[c]) continue;
        out.peak[c] = a;
        out.peak_clip[static_cast<std::size_t>(c)] = static_cast<int>(ci);
        out.peak_frame[static_cast<std::size_t>(c)] = static_cast<int>(f);
      }
    }
  }

  // Which channel's peak sets each limit: its own, or the larger of a mirrored pair's.
  out.limit_from.resize(static_cast<std::size_t>(channels));
  for (int c = 0; c < channels; ++c) out.limit_from[static_cast<std::size_t>(c)] = c;
  if (options.symmetric) {
    out.mirrored_joints = mirrored_joints(s);
    for (const auto& [a, b] : out.mirrored_joints) {
      const motion::Joint &ja = s.joint(a), &jb = s.joint(b);
      for (int k = 0; k < static_cast<int>(ja.channels.size()); ++k) {
        const int ca = ja.first_channel + k, cb = jb.first_channel + k;
        // Both estimated or neither (a pair half in the floating base keeps its own bounds).
        if (!out.estimated[static_cast<std::size_t>(ca)] || !out.estimated[static_cast<std::size_t>(cb)])
          continue;
        const int from = out.peak[ca] >= out.peak[cb] ? ca : cb;
        out.limit_from[static_cast<std::size_t>(ca)] = out.limit_from[static_cast<std::size_t>(cb)] = from;
      }
    }
  }

  out.body = body;
  std::vector<std::string> floored;
  for (int c = 0; c < channels; ++c) {
    if (!out.estimated[static_cast<std::size_t>(c)]) continue;
    const double peak = out.peak[out.limit_from[static_cast<std::size_t>(c)]];
    const double limit = std::max(options.margin * peak, options.floor);
    if (options.margin * peak < options.floor) floored.push_back(s.channel_name(c));
    out.body.torque_min[c] = -limit;
    out.body.torque_max[c] = limit;
  }

  const int estimated = static_cast<int>(std::count(out.estimated.begin(), out.estimated.end(), true));
  out.notes.push_back(std::to_string(estimated) + " channels limited to ±max(" +
                      text::significant(options.margin, 4) + " x peak |τ|, " +
                      text::significant(options.floor, 4) + ") over " + std::to_string(clips.size()) +
                      (clips.size() == 1 ? " clip" : " clips"));
  out.notes.push_back(
      "frames observed at (0, 1): " + std::to_string(out.count(FrameUse::Original)) +
      ", at the hull's point nearest (0, 1): " + std::to_string(out.count(FrameUse::Nearest)) +
      ", in flight: " + std::to_string(out.count(FrameUse::Flight)) +
      ", infeasible at their least-squares point: " + std::to_string(out.count(FrameUse::LeastSquares)) +
      ", infeasible and skipped: " + std::to_string(out.count(FrameUse::Skipped)));
  if (options.symmetric) {
    std::string pairs;
    for (const auto& [a, b] : out.mirrored_joints)
      pairs += (pairs.empty() ? "" : ", ") + s.joint(a).name + "/" + s.joint(b).name;
    out.notes.push_back("mirrored joints sharing limits: " +
                        (pairs.empty() ? std::string("none found") : pairs));
  }
  if (!floored.empty()) {
    std::string list;
    for (const std::string& n : floored) list += (list.empty() ? "" : ", ") + n;
    out.notes.push_back("at the floor (" + text::significant(options.floor, 4) + "): " + list);
  }
  return out;
}

TorqueLimitEstimate estimate_torque_limits(const body::BodyModel& body, const Contacts& contacts,
                                           std::span<const FrameTorques> torques,
                                           const TorqueLimitOptions& options) {
  const ClipLoads clip{&contacts, torques, ""};
  return estimate_torque_limits(body, std::span(&clip, 1), options);
}

}  // namespace kg::retime
