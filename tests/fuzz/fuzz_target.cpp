// Target files (kg/retarget/target.hpp: bones, lengths, morph) under fuzzing, for the synthesized
// walk's skeleton. Refused: a placed kg::Error. Accepted: a target skeleton of the source's
// joints and channels with finite, consistent offsets, key times increasing with one factor per
// joint each, and a finite positive overall scale at every key and between.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "kg/retarget/target.hpp"

namespace {

using kg::fuzz::require;

void check_target_skeleton(const kg::motion::Skeleton& t, const kg::motion::Skeleton& source) {
  kg::fuzz::check_skeleton(t);
  require(t.joint_count() == source.joint_count() && t.channel_count() == source.channel_count(),
          "a target skeleton of other joints or channels");
  for (int j = 0; j < t.joint_count(); ++j)
    require(t.joint(j).name == source.joint(j).name && t.joint(j).parent == source.joint(j).parent,
            "target joint " + t.joint(j).name + " is not the source's");
}

void check_target(const kg::retarget::LoadedTarget& loaded) {
  const kg::retarget::Target& target = loaded.target;
  const kg::motion::Skeleton& source = *kg::fuzz::walk().skeleton;
  require(target.skeleton != nullptr, "a target without a skeleton");
  check_target_skeleton(*target.skeleton, source);
  require(target.key_times.size() == target.key_factors.size(), "key times and factors disagree");
  for (std::size_t k = 0; k < target.key_times.size(); ++k) {
    require(std::isfinite(target.key_times[k]), "a key time not finite");
    require(k == 0 || target.key_times[k] > target.key_times[k - 1], "key times not increasing");
    require(target.key_factors[k].size() == source.joint_count(), "key factors not one per joint");
    require(target.key_factors[k].allFinite(), "a key factor not finite");
  }
  std::vector<double> times{0.0};
  for (std::size_t k = 0; k < target.key_times.size(); ++k) {
    times.push_back(target.key_times[k]);
    if (k + 1 < target.key_times.size())
      times.push_back(0.5 * (target.key_times[k] + target.key_times[k + 1]));
  }
  for (double t : times) {
    const double scale = target.overall_scale(t);
    require(std::isfinite(scale) && scale > 0,
            "overall scale " + std::to_string(scale) + " at t = " + std::to_string(t));
    check_target_skeleton(*target.skeleton_at(t), source);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kg::fuzz::expect_clean("fuzz.yaml", [&] {
    check_target(
        kg::retarget::parse_target_yaml(kg::fuzz::walk().skeleton, kg::fuzz::text(data, size), "fuzz.yaml"));
  });
  return 0;
}
