#include "kg/motion/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "kg/motion/kinematics.hpp"

namespace kg::motion {
namespace {

std::string fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

std::string frame_span(int first, int last) {
  return first == last ? "frame " + std::to_string(first)
                       : "frames " + std::to_string(first) + ".." + std::to_string(last);
}

// Each frame's joints about their centroid (metres): the figure's shape, wherever it stands.
std::vector<Eigen::Matrix3Xd> shapes_of(const Motion& motion) {
  const Eigen::MatrixXd world = joint_world_positions(motion);
  const int joints = static_cast<int>(world.cols() / 3);
  std::vector<Eigen::Matrix3Xd> shapes(static_cast<std::size_t>(world.rows()), Eigen::Matrix3Xd(3, joints));
  for (Eigen::Index f = 0; f < world.rows(); ++f) {
    Eigen::Matrix3Xd& s = shapes[static_cast<std::size_t>(f)];
    for (int j = 0; j < joints; ++j) s.col(j) = world.block<1, 3>(f, 3 * j).transpose();
    s.colwise() -= s.rowwise().mean();
  }
  return shapes;
}

// RMS over joints of the distance between two shapes (metres).
double shape_distance(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  return std::sqrt((a - b).squaredNorm() / static_cast<double>(a.cols()));
}

// The 99th percentile of v[from..] (the largest when there are under 100): a clip's fastest
// motion, one glitch frame ignored.
double fast_level(const std::vector<double>& v, std::size_t from) {
  std::vector<double> rest(v.begin() + static_cast<std::ptrdiff_t>(std::min(from, v.size())), v.end());
  if (rest.empty()) return 0;
  const std::size_t k = rest.size() < 100 ? rest.size() - 1 : (rest.size() * 99) / 100;
  std::nth_element(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(k), rest.end());
  return rest[k];
}

}  // namespace

CalibrationCut detect_calibration_frames(const Motion& motion) {
  CalibrationCut cut;
  const int frames = motion.frame_count();
  if (!motion.skeleton || motion.skeleton->joint_count() < 2 || frames < 3 || !(motion.fps > 0)) {
    cut.evidence = "no calibration frames looked for (needs >= 3 frames of >= 2 joints)";
    return cut;
  }
  const double fps = motion.fps;
  const std::vector<Eigen::Matrix3Xd> shapes = shapes_of(motion);
  std::vector<double> speed(static_cast<std::size_t>(frames), 0.0);  // m/s into frame f
  for (int f = 1; f < frames; ++f)
    speed[static_cast<std::size_t>(f)] =
        shape_distance(shapes[static_cast<std::size_t>(f)], shapes[static_cast<std::size_t>(f) - 1]) * fps;
  auto at = [&](int f) { return speed[static_cast<std::size_t>(f)]; };

  // The peak of the first half, the run of steps around it over a third of it (the jump, or an
  // exporter's blend from the calibration pose), and the steps after it still faster than the
  // later motion's 99th percentile (the blend's ease-out).
  const int half = frames / 2;
  int peak = 1;
  for (int f = 2; f <= half; ++f)
    if (at(f) > at(peak)) peak = f;
  const double run_level = at(peak) / kCalibrationRatio;
  int run_start = peak, first_kept = peak;
  while (run_start > 1 && at(run_start - 1) > run_level) --run_start;
  while (first_kept + 1 < frames && at(first_kept + 1) > run_level) ++first_kept;
  // The level is taken again after each extension, so a blend that itself follows a jump ends
  // where the motion's own speeds start (a few rounds at most; bounded against a hostile clip).
  double later = fast_level(speed, static_cast<std::size_t>(first_kept) + 1);
  for (int round = 0; round < 8; ++round) {
    const int before = first_kept;
    while (first_kept + 1 < frames && at(first_kept + 1) > later) ++first_kept;
    if (first_kept == before) break;
    later = fast_level(speed, static_cast<std::size_t>(first_kept) + 1);
  }
  const double jump =
      shape_distance(shapes[static_cast<std::size_t>(first_kept)], shapes[static_cast<std::size_t>(0)]);
  double held = 0;  // how far the frames before the run stray from frame 0
  for (int f = 1; f < run_start; ++f)
    held = std::max(held, shape_distance(shapes[static_cast<std::size_t>(f)], shapes[0]));

  const std::string peak_text = "the first half's fastest change of shape (into frame " +
                                std::to_string(peak) + ", " + fmt("%.3g", at(peak)) +
                                " m/s RMS about the centroid)";
  std::string failed;
  if (!(at(peak) > kCalibrationSpeed))
    failed = "is not over " + fmt("%g", kCalibrationSpeed) + " m/s";
  else if (!(at(peak) > kCalibrationRatio * later))
    failed = "is not over " + fmt("%g", kCalibrationRatio) + "x the later steps (99th percentile " +
             fmt("%.3g", later) + " m/s)";
  else if (first_kept > half)
    failed = "ends past the first half (frame " + std::to_string(first_kept) + ")";
  else if (!(held * kCalibrationRatio <= jump))
    failed = "does not follow a held pose (" + frame_span(0, run_start - 1) + " stray " + fmt("%.3g", held) +
             " m from frame 0, the change is " + fmt("%.3g", jump) + " m)";
  if (!failed.empty()) {
    cut.evidence = "no calibration frames: " + peak_text + " " + failed;
    return cut;
  }
  cut.frames = first_kept;
  cut.evidence = frame_span(0, first_kept - 1) + (first_kept > 1 ? " are" : " is") + " calibration: " +
                 (run_start > 1 ? "a pose held over " + frame_span(0, run_start - 1) + " (within " +
                                      fmt("%.3g", held) + " m of frame 0), then "
                                : std::string()) +
                 "the shape changes " + fmt("%.3g", jump) + " m RMS about the centroid by frame " +
                 std::to_string(first_kept) + ", at up to " + fmt("%.3g", at(peak)) + " m/s (into frame " +
                 std::to_string(peak) + "), " + fmt("%.3g", at(peak) / std::max(later, 1e-300)) +
                 "x the later steps' 99th percentile (" + fmt("%.3g", later) + " m/s)";
  return cut;
}

}  // namespace kg::motion
