// Key spacing from a band-pass pyramid (§3.7); see key_spacing.hpp for the exact rule.
#include "kg/retarget/key_spacing.hpp"
#include "kg/base/option_check.hpp"
#include "kg/base/text.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <sstream>
#include <stdexcept>

#include "kg/motion/filters.hpp"
#include "kg/motion/skeleton.hpp"

namespace kg::retarget {

namespace {

constexpr double kKernel[5] = {1.0 / 16, 4.0 / 16, 6.0 / 16, 4.0 / 16, 1.0 / 16};

// x at index i, extended past the ends by point reflection (straight lines stay straight);
// reflections farther than the signal is long are clamped to its far end.
inline double extended(const Eigen::VectorXd& x, long i) {
  const long n = x.size();
  if (i < 0) {
    const long m = std::min(-i, n - 1);
    return 2 * x[0] - x[m];
  }
  if (i >= n) {
    const long m = std::min(i - (n - 1), n - 1);
    return 2 * x[n - 1] - x[n - 1 - m];
  }
  return x[i];
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::string fractions_text(const PyramidEnergy& e) {
  std::ostringstream s;
  s.precision(3);
  for (std::size_t k = 0; k < e.fraction.size(); ++k) s << (k ? " " : "") << "L" << k << "=" << e.fraction[k];
  return s.str();
}

}  // namespace

std::vector<Eigen::VectorXd> band_pass_pyramid(const Eigen::Ref<const Eigen::VectorXd>& signal, int levels) {
  if (levels < 1) throw std::invalid_argument("band_pass_pyramid: levels must be >= 1");
  std::vector<Eigen::VectorXd> out;
  out.reserve(static_cast<std::size_t>(levels) + 1);
  Eigen::VectorXd g = signal;
  Eigen::VectorXd next(g.size());
  const long n = g.size();
  for (int k = 0; k < levels; ++k) {
    const long step = 1L << k;
    for (long f = 0; f < n; ++f) {
      double sum = 0;
      for (int i = 0; i < 5; ++i) {
        const long at = f + (i - 2) * step;
        sum += kKernel[i] * (at >= 0 && at < n ? g[at] : extended(g, at));
      }
      next[f] = sum;
    }
    out.push_back(g - next);
    g.swap(next);
  }
  out.push_back(g);
  return out;
}

PyramidEnergy pyramid_energy(const motion::Motion& m, const std::vector<int>& channels, int levels) {
  PyramidEnergy e;
  e.energy.assign(static_cast<std::size_t>(levels), 0.0);
  e.fraction.assign(static_cast<std::size_t>(levels), 0.0);
  const motion::Skeleton& s = *m.skeleton;
  const double height = s.rest_height() > 0 ? s.rest_height() : 1.0;
  Eigen::VectorXd x(m.frame_count());
  for (int c : channels) {
    if (c < 0 || c >= s.channel_count())
      throw std::out_of_range("pyramid_energy: channel " + std::to_string(c) + " out of range");
    const auto [joint, index] = s.channel_owner(c);
    const bool rotation = motion::is_rotation(s.joint(joint).channels[static_cast<std::size_t>(index)].kind);
    for (int f = 0; f < m.frame_count(); ++f) x[f] = m.values(f, c);
    if (rotation) {
      // A jump of more than half a turn between frames is a wrap, not motion.
      motion::unwrap_angles(std::span<double>(x.data(), static_cast<std::size_t>(x.size())));
    } else {
      x /= height;
    }
    if (x.size() == 0) continue;
    const std::vector<Eigen::VectorXd> p = band_pass_pyramid(x, levels);
    for (int k = 0; k < levels; ++k)
      e.energy[static_cast<std::size_t>(k)] += p[static_cast<std::size_t>(k)].squaredNorm();
  }
  double total = 0;
  for (double v : e.energy) total += v;
  if (total > 0)
    for (std::size_t k = 0; k < e.energy.size(); ++k) e.fraction[k] = e.energy[k] / total;
  return e;
}

int spacing_for_energy(const PyramidEnergy& e, double threshold, int* level) {
  int k_star = -1;
  for (std::size_t k = 0; k < e.fraction.size(); ++k)
    if (e.fraction[k] > threshold) {
      k_star = static_cast<int>(k);
      break;
    }
  if (level != nullptr) *level = k_star;
  if (k_star < 0) return 8;
  return std::clamp(1 << std::min(k_star, 3), 2, 8);
}

std::vector<KeyGroup> parse_key_groups(const std::string& text) {
  std::vector<KeyGroup> groups;
  std::size_t start = 0;
  int item = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(';', start), text.size());
    const std::string part = trim(text.substr(start, end - start));
    start = end + 1;
    ++item;
    if (part.empty()) continue;
    const std::string item_name = "groups item " + std::to_string(item);
    const std::string where = item_name + " " + text::excerpt(part);
    const std::size_t eq = part.rfind('=');
    if (eq == std::string::npos)
      throw std::invalid_argument(where + ": expected regex=spacing, e.g. arm|Arm=2");
    const std::string pattern = trim(part.substr(0, eq));
    const std::string number = trim(part.substr(eq + 1));
    if (pattern.empty()) throw std::invalid_argument(where + ": empty joint-name pattern before '='");
    std::size_t used = 0;
    long v = -1;
    try {
      v = std::stol(number, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != number.size() || v < 0 || v > 100000)
      throw std::invalid_argument(where + ": spacing " + text::excerpt(number) +
                                  " is not an integer >= 0 (0 = automatic)");
    try {
      groups.push_back({kg::Pattern::compile(pattern), static_cast<int>(v)});
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(item_name + ": " + e.what());  // the message quotes the pattern
    }
  }
  return groups;
}

void KeySpacingOptions::validate() const {
  using options::require;
  const char* o = "KeySpacingOptions";
  require(threshold > 0 && threshold < 1, o, "threshold", threshold,
          "a fraction of the band energy in (0, 1)");
  require(spacing >= 0, o, "spacing", spacing, ">= 0 frames (0 = automatic)");
  try {
    parse_key_groups(groups);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(o) + ".groups = " + options::value_text(groups) + ": " +
                                e.what());
  }
}

KeySpacing choose_key_spacing(const motion::Motion& m, const KeySpacingOptions& o,
                              std::vector<KeyGroupChoice>* details) {
  if (!m.skeleton) throw std::invalid_argument("choose_key_spacing: motion has no skeleton");
  o.validate();
  const motion::Skeleton& s = *m.skeleton;
  const std::vector<KeyGroup> groups = parse_key_groups(o.groups);

  // Joint -> group (0: none, g + 1: groups[g]); the first matching group wins.
  std::vector<int> group_of(static_cast<std::size_t>(s.joint_count()), 0);
  std::vector<KeyGroupChoice> choices(groups.size() + 1);
  choices[0].spacing = o.spacing;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    choices[g + 1].pattern = groups[g].pattern.text();
    choices[g + 1].spacing = groups[g].spacing;
    bool any = false;
    for (int j = 0; j < s.joint_count(); ++j) {
      if (!groups[g].pattern.partial_match(s.joint(j).name)) continue;
      any = true;
      if (group_of[static_cast<std::size_t>(j)] == 0)
        group_of[static_cast<std::size_t>(j)] = static_cast<int>(g) + 1;
    }
    if (!any)
      throw std::invalid_argument("groups: pattern " + text::excerpt(groups[g].pattern.text()) +
                                  " matches no joint name");
  }
  std::vector<std::vector<int>> channels(choices.size());
  for (int j = 0; j < s.joint_count(); ++j) {
    const int g = group_of[static_cast<std::size_t>(j)];
    choices[static_cast<std::size_t>(g)].joints.push_back(j);
    const motion::Joint& jt = s.joint(j);
    for (std::size_t c = 0; c < jt.channels.size(); ++c)
      channels[static_cast<std::size_t>(g)].push_back(jt.first_channel + static_cast<int>(c));
  }

  KeySpacing out;
  out.fps = m.fps;
  out.frames_per_key.assign(static_cast<std::size_t>(s.channel_count()), 0);
  std::ostringstream reason;
  for (std::size_t g = 0; g < choices.size(); ++g) {
    KeyGroupChoice& c = choices[g];
    c.channels = static_cast<int>(channels[g].size());
    if (c.channels == 0) continue;
    if (c.spacing == 0) {
      c.automatic = true;
      c.energy = pyramid_energy(m, channels[g]);
      c.spacing = spacing_for_energy(c.energy, o.threshold, &c.level);
    }
    for (int ch : channels[g]) out.frames_per_key[static_cast<std::size_t>(ch)] = c.spacing;
    if (reason.tellp() > 0) reason << "; ";
    reason << (c.pattern.empty() ? std::string(groups.empty() ? "all channels" : "other channels")
                                 : "group '" + c.pattern + "'")
           << " (" << c.channels << " channels): " << c.spacing << " frames";
    if (c.automatic) {
      reason << ", pyramid: level energy fractions " << fractions_text(c.energy) << ", threshold "
             << o.threshold;
      if (c.level >= 0)
        reason << ", first level above it L" << c.level;
      else
        reason << ", no level above it";
    } else {
      reason << ", by hand";
    }
  }
  out.reason = reason.str();
  if (details != nullptr) *details = std::move(choices);
  return out;
}

}  // namespace kg::retarget
