// AMC reader (kg/io/asf_amc.hpp) under fuzzing, against the tiny ASF of
// tests/io/test_asf_amc_data.hpp (a root and two leg bones: six, three and one dofs). Refused: a
// placed kg::Error. Accepted: a consistent motion of finite values, the bones' dofs in their
// channels, that imports and writes as BVH.
#include <cstdint>
#include <string>

#include "../io/test_asf_amc_data.hpp"
#include "fuzz_support.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/import_options.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const kg::io::AsfSkeleton asf = kg::io::parse_asf(kg::test::kTinyAsf, "tiny.asf");
  kg::fuzz::expect_clean("fuzz.amc", [&] {
    kg::motion::Motion m = kg::io::parse_amc(kg::fuzz::text(data, size), "fuzz.amc", asf);
    kg::fuzz::check_motion(m);
    kg::fuzz::require(m.skeleton == asf.skeleton, "the motion is not on its ASF's skeleton");
    kg::fuzz::require(m.fps == kg::io::kAmcDefaultFps, "an AMC motion not at the default rate");
    kg::io::apply_import_options(m, {}, kg::io::kAmcDefaultFps, "fuzz.amc", *asf.declared_metres_per_unit());
    kg::fuzz::check_motion(m);
    kg::fuzz::check_writes_as_bvh(m);
  });
  return 0;
}
