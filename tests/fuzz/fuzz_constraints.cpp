// Constraint files (kg/retarget/constraint_io.hpp) under fuzzing, against the synthesized walk.
// Refused: a placed kg::Error. Accepted: every point, channel and sample frame inside the clip,
// params not NaN, finite weights, and every constraint of a built-in kind evaluating without a NaN
// residual (a free side of a range is infinite) at each of its samples on the clip.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "fuzz_support.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/constraint_kinds.hpp"

namespace {

using kg::fuzz::require;

// Params may be infinite (a free side of a range or a region), never NaN.
bool no_nan(const std::vector<double>& v) {
  for (double x : v)
    if (std::isnan(x)) return false;
  return true;
}

void check_set(const kg::retarget::ConstraintSet& set) {
  const kg::motion::Motion& clip = kg::fuzz::walk();
  static const kg::retarget::ConstraintKindTable kinds = kg::retarget::ConstraintKindTable::builtin();
  static const kg::retarget::PoseCache poses(std::span<const kg::motion::Motion>(&clip, 1));
  Eigen::VectorXd residual;
  for (const kg::retarget::Constraint& c : set.constraints) {
    const std::string who = "constraint '" + c.label + "' (" + c.kind + ")";
    for (const kg::motion::PointRef& p : c.points)
      require(
          p.character == 0 && p.joint >= 0 && p.joint < clip.skeleton->joint_count() && p.local.allFinite(),
          who + ": a point outside the skeleton");
    for (const kg::retarget::ChannelRef& ch : c.channels)
      require(ch.character == 0 && ch.channel >= 0 && ch.channel < clip.skeleton->channel_count(),
              who + ": a channel outside the skeleton");
    require(no_nan(c.params) && std::isfinite(c.weight), who + ": a NaN param or a weight not finite");
    for (const kg::retarget::Sample& s : c.samples) {
      require(s.frames.size() == c.points.size() + c.channels.size(), who + ": a sample of the wrong shape");
      for (int f : s.frames)
        require(f >= 0 && f < clip.frame_count(), who + ": frame " + std::to_string(f) + " outside the clip");
      require(no_nan(s.params), who + ": a NaN sample param");
    }
    const kg::retarget::ConstraintKind* kind = kinds.find(c.kind);
    if (kind == nullptr) continue;  // a plugin's kind: checked where the plugin is loaded
    for (const kg::retarget::Sample& s : c.samples) {
      kg::retarget::evaluate_sample(*kind, c, s, poses, residual);
      require(!residual.hasNaN(), who + ": a NaN residual on the clip");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(kg::fuzz::text(data, size));
  kg::fuzz::expect_clean("fuzz.yaml", [&] {
    check_set(kg::retarget::read_constraints_string(
        text, "fuzz.yaml", std::span<const kg::motion::Motion>(&kg::fuzz::walk(), 1)));
  });
  return 0;
}
