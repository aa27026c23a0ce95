#include "kg/motion/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace kg::motion {

namespace {

void check_sizes(int frames, int spacing) {
  if (frames < 1)
    throw std::invalid_argument("B-spline: " + std::to_string(frames) + " frames (expected >= 1)");
  if (spacing < 1)
    throw std::invalid_argument("B-spline: key spacing " + std::to_string(spacing) +
                                " frames (expected >= 1)");
}

BasisAt basis_of(int segment, double s) {
  return {.first = segment, .weight = cubic_bspline_weights(s).value};
}

}  // namespace

CubicWeights cubic_bspline_weights(double s) {
  const double s2 = s * s, s3 = s2 * s, t = 1 - s;
  return {.value = {t * t * t / 6, (3 * s3 - 6 * s2 + 4) / 6, (-3 * s3 + 3 * s2 + 3 * s + 1) / 6, s3 / 6},
          .first = {-t * t / 2, (3 * s2 - 4 * s) / 2, (-3 * s2 + 2 * s + 1) / 2, s2 / 2},
          .second = {t, 3 * s - 2, -3 * s + 1, s}};
}

int bspline_segment_count(int frames, int spacing) {
  check_sizes(frames, spacing);
  return std::max(1, (frames - 1 + spacing - 1) / spacing);
}

int bspline_control_count(int frames, int spacing) {
  return bspline_segment_count(frames, spacing) + 3;
}

BasisAt bspline_basis_at(double frame, int frames, int spacing) {
  const int segments = bspline_segment_count(frames, spacing);
  if (!(frame >= 0 && frame <= frames - 1))
    throw std::out_of_range("B-spline: frame " + std::to_string(frame) + " outside [0, " +
                            std::to_string(frames - 1) + "]");
  const double u = frame / spacing;
  const int segment = std::min(static_cast<int>(std::floor(u)), segments - 1);
  return basis_of(segment, u - segment);
}

BasisAt bspline_basis(int frame, int frames, int spacing) {
  return bspline_basis_at(static_cast<double>(frame), frames, spacing);
}

}  // namespace kg::motion
