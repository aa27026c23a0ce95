// Test support: tables of invalid settings for an Options struct's validate() (DESIGN.md 15).
//
//   kg::test::check_option_table<HullOptions>({
//       {"HullOptions.tolerance = nan", [](auto& o) { o.tolerance = kg::test::kNaN; }},
//   });
//
// Each row changes one field of a valid Options (default-constructed, or `good`) and expects
// validate() to throw std::invalid_argument whose message holds `message` ("Struct.field =
// value") and "expected"; the valid Options itself must pass.
#pragma once

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

namespace kg::test {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

template <class Options>
struct BadOption {
  std::string message;  // what the message must hold: "Struct.field = value"
  std::function<void(Options&)> change;
};

template <class Options>
void check_option_table(const Options& good, const std::vector<BadOption<Options>>& table) {
  REQUIRE_NOTHROW(good.validate());
  for (const BadOption<Options>& bad : table) {
    Options o = good;
    bad.change(o);
    INFO(bad.message);
    CHECK_THROWS_AS(o.validate(), std::invalid_argument);
    CHECK_THROWS_WITH(o.validate(),
                      Catch::Matchers::Contains(bad.message) && Catch::Matchers::Contains("expected"));
  }
}

template <class Options>
void check_option_table(const std::vector<BadOption<Options>>& table) {
  check_option_table(Options{}, table);
}

}  // namespace kg::test
