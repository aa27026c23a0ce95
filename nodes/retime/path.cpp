#include "kg/retime/path.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/QR>

#include "kg/motion/rotations.hpp"

namespace kg::retime {

namespace {

// Each column convolved with a normalised Gaussian of `sigma` frames. Past each end the clip
// continues as the least-squares parabola through the frames within the kernel's reach of that
// end (the whole clip when it is shorter than the kernel; the line through two frames): a
// parabola, a ballistic flight, keeps its second derivative exactly to the last frame, where
// an odd reflection would bend it straight, and a clip shorter than the kernel reads nothing
// outside itself.
motion::FrameMatrix gaussian_smoothed(const motion::FrameMatrix& q, double sigma) {
  const int frames = static_cast<int>(q.rows());
  const int radius = static_cast<int>(std::ceil(4 * sigma));
  std::vector<double> kernel(static_cast<std::size_t>(2 * radius + 1));
  double sum = 0;
  for (int k = -radius; k <= radius; ++k) sum += kernel[static_cast<std::size_t>(k + radius)] = std::exp(-0.5 * k * k / (sigma * sigma));
  for (double& w : kernel) w /= sum;
  // The continuations: coefficients of powers of u = (frames from the end, inwards) / reach.
  const int reach = std::min(frames, radius + 1);
  const int degree = std::min(2, reach - 1);
  Eigen::MatrixXd powers(reach, degree + 1);
  for (int k = 0; k < reach; ++k)
    for (int d = 0; d <= degree; ++d) powers(k, d) = std::pow(static_cast<double>(k) / reach, d);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> fit(powers);
  const Eigen::MatrixXd head = fit.solve(Eigen::MatrixXd(q.topRows(reach)));
  const Eigen::MatrixXd tail = fit.solve(Eigen::MatrixXd(q.bottomRows(reach).colwise().reverse()));
  auto continued = [&](const Eigen::MatrixXd& coefficients, int inwards, Eigen::Index c) {
    const double u = static_cast<double>(inwards) / reach;
    double v = 0;
    for (int d = degree; d >= 0; --d) v = v * u + coefficients(d, c);
    return v;
  };
  auto at = [&](int f, Eigen::Index c) {
    if (f < 0) return continued(head, f, c);
    if (f >= frames) return continued(tail, frames - 1 - f, c);
    return q(f, c);
  };
  motion::FrameMatrix out(q.rows(), q.cols());
  for (Eigen::Index c = 0; c < q.cols(); ++c)
    for (int f = 0; f < frames; ++f) {
      double v = 0;
      for (int k = -radius; k <= radius; ++k) v += kernel[static_cast<std::size_t>(k + radius)] * at(f + k, c);
      out(f, c) = v;
    }
  return out;
}

}  // namespace

PathDerivatives path_derivatives(const motion::Motion& motion, double smoothing) {
  motion.check();
  if (!(smoothing >= 0) || !std::isfinite(smoothing))
    throw std::invalid_argument("path derivatives: smoothing " + std::to_string(smoothing) + " s (expected >= 0)");
  const motion::Skeleton& skeleton = *motion.skeleton;
  const int frames = motion.frame_count();
  const int channels = skeleton.channel_count();
  PathDerivatives d{motion::FrameMatrix::Zero(frames, channels), motion::FrameMatrix::Zero(frames, channels)};
  if (frames < 2) return d;

  // Values with rotation channels unwrapped along the clip (each frame's angle nearest the last).
  motion::FrameMatrix q = motion.values;
  for (int c = 0; c < channels; ++c) {
    auto [joint, index] = skeleton.channel_owner(c);
    if (!motion::is_rotation(skeleton.joint(joint).channels[static_cast<std::size_t>(index)].kind)) continue;
    for (int f = 1; f < frames; ++f) q(f, c) = motion::nearest_angle(q(f, c), q(f - 1, c));
  }
  if (smoothing * motion.fps > 0.05) q = gaussian_smoothed(q, smoothing * motion.fps);
  const double h = 1.0 / motion.fps;
  if (frames == 2) {
    d.first.row(0) = (q.row(1) - q.row(0)) / h;
    d.first.row(1) = d.first.row(0);
    return d;
  }
  for (int f = 1; f + 1 < frames; ++f) {
    d.first.row(f) = (q.row(f + 1) - q.row(f - 1)) / (2 * h);
    d.second.row(f) = (q.row(f + 1) - 2 * q.row(f) + q.row(f - 1)) / (h * h);
  }
  const int last = frames - 1;
  d.first.row(0) = (-3 * q.row(0) + 4 * q.row(1) - q.row(2)) / (2 * h);
  d.first.row(last) = (3 * q.row(last) - 4 * q.row(last - 1) + q.row(last - 2)) / (2 * h);
  if (frames >= 4) {
    d.second.row(0) = (2 * q.row(0) - 5 * q.row(1) + 4 * q.row(2) - q.row(3)) / (h * h);
    d.second.row(last) = (2 * q.row(last) - 5 * q.row(last - 1) + 4 * q.row(last - 2) - q.row(last - 3)) / (h * h);
  } else {
    d.second.row(0) = d.second.row(1);
    d.second.row(last) = d.second.row(1);
  }
  return d;
}

}  // namespace kg::retime
