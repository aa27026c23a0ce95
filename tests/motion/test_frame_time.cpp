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
