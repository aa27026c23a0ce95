// seconds_to_frame: times read from files become frames only inside the clip, checked before the
// cast (issue 13: lround(t * fps) of 35791394.2 s at 30 fps wrapped to a valid frame).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/motion/frame_time.hpp"

using kg::motion::seconds_to_frame;

TEST_CASE("seconds_to_frame rounds inside the clip and refuses the rest") {
  CHECK(seconds_to_frame(0, 30, 60) == 0);
  CHECK(seconds_to_frame(1.25, 30, 60) == 38);
  CHECK(seconds_to_frame(59.4 / 30, 30, 60) == 59);
  CHECK(seconds_to_frame(-0.4 / 30, 30, 60) == 0);
  const double bad[] = {59.5 / 30,
                        3.0,
                        35791394.2,
                        1e300,
                        -1.0,
                        std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::quiet_NaN()};
  for (double t : bad) {
    INFO(t);
    CHECK_THROWS_AS(seconds_to_frame(t, 30, 60), std::out_of_range);
  }
  CHECK_THROWS_WITH(seconds_to_frame(35791394.2, 30, 60),
                    "35791394.2 s is outside the clip (0..1.96667 s, frames 0..59 at 30 fps)");
  CHECK_THROWS_AS(seconds_to_frame(0, 30, 0), std::out_of_range);  // no frames: no time is inside
}

TEST_CASE("rate_of_printed_frame_time: the rate a header's rounded digits stand for") {
  using kg::motion::rate_of_printed_frame_time;
  const auto rate = [](const char* printed) {
    return rate_of_printed_frame_time(printed, std::stod(printed));
  };
  // Rounded 1/n and 1000/1001 n (issue 14: "0.0333333" is 30.00003 fps, and resampling a clip to
  // its own 30 fps lost its last frame).
  CHECK(rate("0.0333333") == 30);
  CHECK(rate("0.033333333") == 30);
  CHECK(rate("3.33333e-02") == 30);
  CHECK(rate("0.008333") == 120);
  CHECK(rate("0.0416667") == 24);
  CHECK(rate("0.0166667") == 60);
  CHECK(rate("0.0333667") == Approx(30000.0 / 1001).epsilon(1e-15));
  CHECK(rate("0.04") == 25);
  CHECK(rate("1") == 1);
  // Digits that do not fix the rate to 1e-4, or that no such rate prints as, keep 1/value.
  CHECK(rate("0.03") == 1 / 0.03);
  CHECK(rate("0.0333") == 1 / 0.0333);
  CHECK(rate("0.0333300") == 1 / 0.03333);
  CHECK(rate("0.011") == 1 / 0.011);
  CHECK(rate("2.5") == 1 / 2.5);
  CHECK(rate_of_printed_frame_time("not a number", 0.0333333) == 1 / 0.0333333);
}
