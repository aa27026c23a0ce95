// Body files (kg/body/body_build.hpp: mass table, classes, segment overrides, torque limits)
// under fuzzing, built on the synthesized walk's skeleton. Refused: a placed kg::Error, from
// reading the file or from building its body on the skeleton. Accepted: a body model that passes
// check_body_model, of finite positive total mass, whose centre of mass at the clip's first frame
// is finite.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "kg/body/body_build.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kg::fuzz::expect_clean("fuzz.yaml", [&] {
    const kg::body::LoadedBodySpec loaded =
        kg::body::parse_body_yaml(kg::fuzz::text(data, size), "fuzz.yaml");
    const kg::motion::Motion& clip = kg::fuzz::walk();
    const kg::body::BuiltBody built = kg::body::build_body_model(clip.skeleton, loaded.spec);
    kg::body::check_body_model(built.body);
    const double mass = built.body.total_mass();
    kg::fuzz::require(std::isfinite(mass) && mass > 0, "a body of total mass " + std::to_string(mass));
    kg::fuzz::require(kg::body::body_com(built.body, clip.values.row(0)).allFinite(),
                      "a centre of mass not finite");
  });
  return 0;
}
