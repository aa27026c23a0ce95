#include "kg/motion/motion.hpp"
#include "kg/motion/frame_time.hpp"

#include "kg/base/text.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace kg::motion {

void Motion::check() const {
  const std::string who = "motion '" + name + "'";
  if (!skeleton) throw std::invalid_argument(who + ": no skeleton");
  if (values.cols() != skeleton->channel_count())
    throw std::invalid_argument(who + ": " + std::to_string(values.cols()) +
                                " values per frame, but the skeleton has " +
                                std::to_string(skeleton->channel_count()) + " channels");
  if (!std::isfinite(fps) || !(fps > 0)) {
    std::ostringstream s;
    s << who << ": frame rate " << fps << " (expected a finite number > 0)";
    throw std::invalid_argument(s.str());
  }
  if (values.allFinite()) return;
  for (Eigen::Index f = 0; f < values.rows(); ++f)
    for (Eigen::Index c = 0; c < values.cols(); ++c)
      if (!std::isfinite(values(f, c))) {
        std::ostringstream s;
        s << who << ": frame " << f << ", channel " << skeleton->channel_name(static_cast<int>(c)) << " is "
          << values(f, c) << " (expected a finite number)";
        throw std::invalid_argument(s.str());
      }
}

Motion frame_range(const Motion& motion, int first, int last) {
  const int frames = motion.frame_count();
  const int end = last == -1 ? frames - 1 : last;
  if (first < 0 || end >= frames || first > end || last < -1)
    throw std::invalid_argument("motion '" + motion.name + "': frames " + std::to_string(first) + " to " +
                                (last == -1 ? "the last" : std::to_string(last)) + " of its " +
                                std::to_string(frames) + " (expected 0 <= first <= last < " +
                                std::to_string(frames) + "; last -1: the last frame)");
  return {motion.skeleton, motion.values.middleRows(first, end - first + 1), motion.fps, motion.name};
}

int seconds_to_frame(double seconds, double fps, int frame_count) {
  const double f = seconds * fps;  // in double: no cast before the range check
  // Rounds into 0..frame_count-1: -0.5 < f < frame_count - 0.5 (lround rounds halves away from 0).
  if (!(std::isfinite(f) && f > -0.5 && f < frame_count - 0.5)) {
    // Ten digits: a time that wrapped to a frame, as 35791394.2 s did, shows whole.
    throw std::out_of_range(text::significant(seconds, 10) + " s is outside the clip (0.." +
                            text::significant(frame_count > 1 ? (frame_count - 1) / fps : 0.0) +
                            " s, frames 0.." + std::to_string(frame_count - 1) + " at " +
                            text::significant(fps) + " fps)");
  }
  return static_cast<int>(std::lround(f));
}

}  // namespace kg::motion
