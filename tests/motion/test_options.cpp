// FootplantOptions::validate() (DESIGN.md 15): a table of invalid settings, each refused with
// std::invalid_argument naming the field and the value; the defaults and the documented special
// values (NaN floor: estimated; trim_distance 0: no trimming) pass; detect_footplants refuses a
// bad setting before it reads the motion.
#include <catch2/catch.hpp>

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "../support/option_table.hpp"
#include "kg/motion/footplants.hpp"
#include "kg/motion/motion.hpp"

using namespace kg::motion;
using Catch::Matchers::Contains;

TEST_CASE("FootplantOptions::validate refuses each field out of range") {
  using kg::test::kInf;
  using kg::test::kNaN;
  using Bad = kg::test::BadOption<FootplantOptions>;
  const std::vector<Bad> table = {
      {"FootplantOptions.height_threshold = 0.0", [](auto& o) { o.height_threshold = 0; }},
      {"FootplantOptions.speed_threshold = -0.1", [](auto& o) { o.speed_threshold = -0.1; }},
      {"FootplantOptions.speed_threshold = nan", [](auto& o) { o.speed_threshold = kNaN; }},
      {"FootplantOptions.hysteresis = 0.5", [](auto& o) { o.hysteresis = 0.5; }},
      {"FootplantOptions.hysteresis = inf", [](auto& o) { o.hysteresis = kInf; }},
      {"FootplantOptions.min_duration_s = -1.0", [](auto& o) { o.min_duration_s = -1; }},
      {"FootplantOptions.min_duration_frames = 0", [](auto& o) { o.min_duration_frames = 0; }},
      {"FootplantOptions.floor = inf", [](auto& o) { o.floor = kInf; }},
      {"FootplantOptions.floor = -inf", [](auto& o) { o.floor = -kInf; }},
      {"FootplantOptions.floor_percentile = 0.6", [](auto& o) { o.floor_percentile = 0.6; }},
      {"FootplantOptions.floor_percentile = -0.1", [](auto& o) { o.floor_percentile = -0.1; }},
      {"FootplantOptions.trim_distance = -0.01", [](auto& o) { o.trim_distance = -0.01; }},
      {"FootplantOptions.rest_window_s = nan", [](auto& o) { o.rest_window_s = kNaN; }},
      {"FootplantOptions.body_relative = 1.0", [](auto& o) { o.body_relative = 1; }},
      {"FootplantOptions.run_froude = 0.0", [](auto& o) { o.run_froude = 0; }},
      {"FootplantOptions.bridge_s = -0.1", [](auto& o) { o.bridge_s = -0.1; }},
      {"FootplantOptions.bridge_distance = nan", [](auto& o) { o.bridge_distance = kNaN; }},
      {"FootplantOptions.character = -1", [](auto& o) { o.character = -1; }},
  };
  REQUIRE_NOTHROW(FootplantOptions{}.validate());
  for (const Bad& bad : table) {
    FootplantOptions o;
    bad.change(o);
    INFO(bad.message);
    CHECK_THROWS_AS(o.validate(), std::invalid_argument);
    CHECK_THROWS_WITH(o.validate(), Contains(bad.message) && Contains("expected"));
    CHECK_THROWS_WITH(detect_footplants(Motion{}, o), Contains(bad.message) || Contains("no skeleton"));
  }
  FootplantOptions special;
  special.floor = 0.0;
  special.trim_distance = 0;
  special.rest_window_s = 0;
  special.min_duration_s = 0;
  special.floor_percentile = 0.5;
  CHECK_NOTHROW(special.validate());
}
