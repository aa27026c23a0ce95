// ASF reader (kg/io/asf_amc.hpp) under fuzzing. Refused: a placed kg::Error. Accepted: a
// consistent skeleton whose bones map onto its joints and channels, on which an AMC file of two
// frames of zeros (every bone's dofs, in the file's order) reads into a consistent motion that
// imports (units as declared) and writes as BVH.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/import_options.hpp"

namespace {

using kg::fuzz::require;

void check_bones(const kg::io::AsfSkeleton& asf) {
  const kg::motion::Skeleton& s = *asf.skeleton;
  require(!asf.bones.empty() && asf.bones[0].name == "root", "bones[0] is not the root");
  for (const kg::io::AsfBone& bone : asf.bones) {
    require(bone.joint >= 0 && bone.joint < s.joint_count(), "bone " + bone.name + " has no joint");
    require(bone.targets.size() == bone.dofs.size(), "bone " + bone.name + " has dofs without targets");
    for (int target : bone.targets)
      require(target >= 0 && target < s.channel_count(), "bone " + bone.name + " targets no channel");
  }
}

std::string zero_amc(const kg::io::AsfSkeleton& asf) {
  std::string amc = ":FULLY-SPECIFIED\n:RADIANS\n";
  for (int frame = 1; frame <= 2; ++frame) {
    amc += std::to_string(frame) + "\n";
    for (const kg::io::AsfBone& bone : asf.bones) {
      if (bone.dofs.empty()) continue;
      amc += bone.name;
      for (std::size_t d = 0; d < bone.dofs.size(); ++d) amc += " 0";
      amc += "\n";
    }
  }
  return amc;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kg::fuzz::expect_clean("fuzz.asf", [&] {
    const kg::io::AsfSkeleton asf = kg::io::parse_asf(kg::fuzz::text(data, size), "fuzz.asf");
    require(asf.skeleton != nullptr, "an accepted ASF without a skeleton");
    kg::fuzz::check_skeleton(*asf.skeleton);
    check_bones(asf);
    kg::motion::Motion m = kg::io::parse_amc(zero_amc(asf), "zeros.amc", asf);
    require(m.frame_count() == 2, "two AMC frames read as " + std::to_string(m.frame_count()));
    kg::fuzz::check_motion(m);
    kg::io::ImportOptions options;
    options.units = asf.declared_metres_per_unit() ? "auto" : "m";
    kg::io::apply_import_options(m, options, kg::io::kAmcDefaultFps, "fuzz.asf",
                                 asf.declared_metres_per_unit().value_or(0));
    kg::fuzz::check_motion(m);
    kg::fuzz::check_writes_as_bvh(m);
  });
  return 0;
}
