#include "kg/motion/motion.hpp"
#include "kg/motion/frame_time.hpp"

#include "kg/base/text.hpp"

#include <charconv>
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

namespace {

// The place value of the last digit of a decimal number as written ("0.0333333": 1e-7,
// "8.333e-3": 1e-6, "30": 1); 0 when `printed` is not such a number.
double last_digit_place(std::string_view printed) {
  std::size_t i = 0;
  if (i < printed.size() && (printed[i] == '+' || printed[i] == '-')) ++i;
  int digits = 0, after_point = 0;
  bool point = false;
  for (; i < printed.size(); ++i) {
    const char c = printed[i];
    if (c >= '0' && c <= '9') {
      ++digits, after_point += point;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      break;
    }
  }
  int exponent = 0;
  if (i < printed.size() && (printed[i] == 'e' || printed[i] == 'E')) {
    ++i;
    if (i < printed.size() && printed[i] == '+') ++i;
    const auto [end, ec] = std::from_chars(printed.data() + i, printed.data() + printed.size(), exponent);
    if (ec != std::errc() || end != printed.data() + printed.size()) return 0;
  } else if (i != printed.size()) {
    return 0;
  }
  if (digits == 0 || exponent < -300 || exponent > 300) return 0;
  return std::pow(10.0, exponent - after_point);
}

}  // namespace

double rate_of_printed_frame_time(std::string_view printed, double seconds) {
  const double raw = 1.0 / seconds;
  const double half_place = 0.5 * last_digit_place(printed);
  if (!(seconds > 0) || !std::isfinite(raw) || half_place == 0) return raw;
  const bool digits_fix_rate = half_place <= 1e-4 * seconds;
  for (const double per_rate : {1.0, 1.001}) {  // n / per_rate: integer and NTSC rates
    const double n = std::round(raw * per_rate);
    if (n < 1) continue;
    const double rate = n / per_rate;
    const double off = std::abs(1.0 / rate - seconds);
    // The 1e-12 admits a rate the value already is, but for its binary rounding ("0.04").
    if ((digits_fix_rate && off <= half_place * (1 + 1e-9)) || off <= 1e-12 * seconds) return rate;
  }
  return raw;
}

}  // namespace kg::motion
