#include "kg/motion/motion.hpp"

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

}  // namespace kg::motion
