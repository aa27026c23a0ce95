// BVH reader (kg/io/bvh.hpp) under fuzzing. Refused: a placed kg::Error. Accepted: a consistent
// motion that round-trips through the writer: written (6 decimals) and read back it has the same
// joints, channels, End Sites, frames and rate, every number within the printed precision, and
// written again it is the same text (when every number is below 1e6 in magnitude, so that six
// decimals lie within a double's precision). Import options (auto units and up) either refuse
// at the file or give a consistent motion.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

#include "fuzz_support.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"

namespace {

using kg::fuzz::require;

constexpr int kPrecision = 6;

// |a - b| within half the last printed decimal of a value printed in `scale` units, plus a few
// rounding errors of the magnitude.
bool within_print(double a, double b, double scale) {
  const double half_digit = 0.5 * std::pow(10.0, -kPrecision) / scale;
  return std::abs(a - b) <= half_digit * 1.000001 + 8 * 2.3e-16 * std::max(std::abs(a), std::abs(b));
}

void check_round_trip(const kg::io::BvhClip& clip) {
  const kg::motion::Motion& m = clip.motion;
  const kg::motion::Skeleton& s = *m.skeleton;
  const std::string once = kg::io::write_bvh_string(m, {.precision = kPrecision, .exact = true});
  const kg::io::BvhClip again = kg::io::parse_bvh(once, "written.bvh");
  const kg::motion::Skeleton& t = *again.motion.skeleton;
  require(t.joint_count() == s.joint_count(), "the written file has another number of joints");
  require(t.channel_count() == s.channel_count(), "the written file has another number of channels");
  require(again.motion.frame_count() == m.frame_count(), "the written file has another number of frames");
  require(std::abs(again.motion.fps - m.fps) <= 1e-8 * m.fps, "the written file has another frame rate");

  double largest = 0;
  for (int j = 0; j < s.joint_count(); ++j) {
    const kg::motion::Joint& a = s.joint(j);
    const kg::motion::Joint& b = t.joint(j);
    require(a.name == b.name && a.parent == b.parent, "joint " + a.name + " written as " + b.name);
    require(a.channels.size() == b.channels.size(), "joint " + a.name + " written with other channels");
    for (std::size_t c = 0; c < a.channels.size(); ++c)
      require(a.channels[c].kind == b.channels[c].kind,
              "joint " + a.name + " written with another channel order");
    require(a.end_sites.size() == b.end_sites.size(), "joint " + a.name + " written with other End Sites");
    for (int i = 0; i < 3; ++i) {
      require(within_print(a.offset[i], b.offset[i], 1), "joint " + a.name + "'s offset not kept");
      largest = std::max(largest, std::abs(a.offset[i]));
      for (std::size_t e = 0; e < a.end_sites.size(); ++e) {
        require(within_print(a.end_sites[e][i], b.end_sites[e][i], 1),
                "an End Site of " + a.name + " not kept");
        largest = std::max(largest, std::abs(a.end_sites[e][i]));
      }
    }
  }
  for (int c = 0; c < s.channel_count(); ++c) {
    const auto [joint, index] = s.channel_owner(c);
    const bool rotation =
        kg::motion::is_rotation(s.joint(joint).channels[static_cast<std::size_t>(index)].kind);
    const double scale = rotation ? 180 / std::numbers::pi : 1;  // printed in degrees
    for (int f = 0; f < m.frame_count(); ++f) {
      require(within_print(m.values(f, c), again.motion.values(f, c), scale),
              "frame " + std::to_string(f) + " channel " + s.channel_name(c) + " not kept");
      largest = std::max(largest, std::abs(m.values(f, c)) * scale);
    }
  }
  if (largest < 1e6)
    require(kg::io::write_bvh_string(again.motion, {.precision = kPrecision, .exact = true}) == once,
            "read, written, read and written again the text changes");

  // The default layout, which every tool reads: three rotation channels per joint, three
  // position channels or none.
  const kg::io::BvhClip standard =
      kg::io::parse_bvh(kg::io::write_bvh_string(m, {.precision = kPrecision}), "standard.bvh");
  require(standard.motion.skeleton->joint_count() == s.joint_count(), "the standard layout lost joints");
  for (const kg::motion::Joint& j : standard.motion.skeleton->joints())
    require(j.channels.size() == 3 || j.channels.size() == 6,
            "joint " + j.name + " written with " + std::to_string(j.channels.size()) + " channels");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kg::fuzz::expect_clean("fuzz.bvh", [&] {
    const kg::io::BvhClip clip = kg::io::parse_bvh(kg::fuzz::text(data, size), "fuzz.bvh");
    kg::fuzz::check_motion(clip.motion);
    require(clip.frame_time >= kg::io::kBvhMinFrameTime && clip.frame_time <= kg::io::kBvhMaxFrameTime,
            "a frame time outside the accepted range");
    check_round_trip(clip);
    kg::motion::Motion imported = clip.motion;
    kg::io::apply_import_options(imported, {}, 1 / clip.frame_time, "fuzz.bvh");
    kg::fuzz::check_motion(imported);
  });
  return 0;
}
