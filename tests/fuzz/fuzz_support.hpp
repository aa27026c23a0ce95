// What every fuzz harness of tests/fuzz checks besides "no crash": a refused input is refused
// with a kg::Error placed in the file (its what() starts "<file>:"), nothing else escapes, and
// what is accepted is consistent. A finding prints what is wrong and aborts, so libFuzzer keeps
// the input and a replay (replay_main.cpp) fails with the message.
//
//   extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
//     kg::fuzz::expect_clean("x.bvh", [&] { check(kg::io::parse_bvh(kg::fuzz::text(data, size), "x.bvh"));
//     }); return 0;
//   }
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>
#include <string_view>

#include "kg/base/error.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/motion.hpp"
#include "kg/motion/skeleton.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg::fuzz {

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline void require(bool ok, const std::string& what) {
  if (!ok) finding(what);
}

// Runs `body`; a kg::Error must name `file` first (file:line[:column]: ...), and any other
// exception is a finding (a std::invalid_argument, a bad_alloc: a message without a place, or
// memory the input should never have asked for). With KG_FUZZ_SHOW=1 in the environment, each
// input's outcome is printed (which seeds a reader accepts, and why it refuses the others).
template <class Body>
void expect_clean(const std::string& file, Body&& body) {
  static const bool show = std::getenv("KG_FUZZ_SHOW") != nullptr;
  try {
    body();
    if (show) std::fprintf(stderr, "accepted\n");
  } catch (const kg::Error& e) {
    const std::string what = e.what();
    if (show) std::fprintf(stderr, "refused: %s\n", what.c_str());
    require(what.rfind(file + ":", 0) == 0, "an error without its place in " + file + ": " + what);
    require(what.size() < 4096, "an error of " + std::to_string(what.size()) + " bytes (quotes too much)");
  } catch (const std::bad_alloc&) {
    finding("std::bad_alloc: the input made the reader allocate without bound");
  } catch (const std::exception& e) {
    finding(std::string("an exception that is not a placed kg::Error: ") + e.what());
  }
}

// The invariants every reader's skeleton keeps: parents before children, channels numbered
// contiguously in joint order, names unique and found by find_joint, finite offsets and axes.
inline void check_skeleton(const motion::Skeleton& s) {
  int channel = 0;
  for (int j = 0; j < s.joint_count(); ++j) {
    const motion::Joint& joint = s.joint(j);
    require(joint.parent >= -1 && joint.parent < j,
            "joint " + joint.name + " has parent " + std::to_string(joint.parent) + " not before it");
    require(joint.first_channel == channel, "joint " + joint.name + " channels not contiguous");
    channel += static_cast<int>(joint.channels.size());
    require(s.find_joint(joint.name) == j, "joint name '" + joint.name + "' not found at its index");
    require(joint.offset.allFinite() && joint.axis.allFinite(), "joint " + joint.name + " not finite");
    for (const auto& e : joint.end_sites)
      require(e.allFinite(), "an End Site of " + joint.name + " not finite");
  }
  require(channel == s.channel_count(), "channel_count disagrees with the joints' channels");
  require(s.file_to_world.allFinite() && std::isfinite(s.source_unit_metres) && s.source_unit_metres > 0,
          "file_to_world or source_unit_metres not finite");
}

// An accepted motion passes Motion::check (sizes, fps, finite values) and check_skeleton.
inline void check_motion(const motion::Motion& m) {
  require(m.skeleton != nullptr, "a motion without a skeleton");
  check_skeleton(*m.skeleton);
  try {
    m.check();
  } catch (const std::exception& e) {
    finding(std::string("an accepted motion fails Motion::check: ") + e.what());
  }
}

// The clip the files about a clip (targets, constraints, contacts, bodies) are read against: a
// synthesized walk of two steps at 30 fps (the synthesized figure's joints and frame count).
inline const motion::Motion& walk() {
  static const motion::Motion m = synth::synthesize_walk({.steps = 2, .fps = 30}).motion;
  return m;
}

// An accepted motion from any reader can be written as BVH, and the written file reads back
// with the same joints in the same order and the same number of frames.
inline void check_writes_as_bvh(const motion::Motion& m) {
  const std::string written = io::write_bvh_string(m);
  const io::BvhClip back = io::parse_bvh(written, "written.bvh");
  const motion::Skeleton& s = *m.skeleton;
  const motion::Skeleton& t = *back.motion.skeleton;
  require(t.joint_count() == s.joint_count(), "written as BVH, another number of joints");
  for (int j = 0; j < s.joint_count(); ++j)
    require(t.joint(j).name == s.joint(j).name && t.joint(j).parent == s.joint(j).parent,
            "written as BVH, joint " + s.joint(j).name + " became " + t.joint(j).name);
  require(back.motion.frame_count() == m.frame_count(), "written as BVH, another number of frames");
}

}  // namespace kg::fuzz
