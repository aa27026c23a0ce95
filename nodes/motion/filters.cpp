#include "kg/motion/filters.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/QR>

namespace kg::motion {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// The continuation of every column past one end as a least-squares polynomial of degree <= 2 in
// u = (samples from the end, inwards) / reach, fitted to the `reach` samples nearest that end.
class ParabolaEnds {
 public:
  ParabolaEnds(const Eigen::MatrixXd& curves, int radius) {
    const int samples = static_cast<int>(curves.rows());
    reach_ = std::min(samples, radius + 1);
    degree_ = std::min(2, reach_ - 1);
    Eigen::MatrixXd powers(reach_, degree_ + 1);
    for (int k = 0; k < reach_; ++k)
      for (int d = 0; d <= degree_; ++d) powers(k, d) = std::pow(static_cast<double>(k) / reach_, d);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> fit(powers);
    head_ = fit.solve(Eigen::MatrixXd(curves.topRows(reach_)));
    tail_ = fit.solve(Eigen::MatrixXd(curves.bottomRows(reach_).colwise().reverse()));
  }
  // `inwards` < 0 samples before the first (head) or after the last (tail).
  double before(int inwards, Eigen::Index c) const { return value(head_, inwards, c); }
  double after(int inwards, Eigen::Index c) const { return value(tail_, inwards, c); }

 private:
  double value(const Eigen::MatrixXd& coefficients, int inwards, Eigen::Index c) const {
    const double u = static_cast<double>(inwards) / reach_;
    double v = 0;
    for (int d = degree_; d >= 0; --d) v = v * u + coefficients(d, c);
    return v;
  }
  int reach_ = 0;
  int degree_ = 0;
  Eigen::MatrixXd head_, tail_;
};

}  // namespace

std::vector<int> unwrap_turns(std::span<const double> angles) {
  std::vector<int> turns(angles.size(), 0);
  int turn = 0;
  for (std::size_t i = 1; i < angles.size(); ++i) {
    const double step = angles[i] - angles[i - 1];
    if (std::abs(step) > std::numbers::pi) turn -= static_cast<int>(std::lround(step / kTwoPi));
    turns[i] = turn;
  }
  return turns;
}

std::vector<int> unwrap_angles(std::span<double> angles) {
  std::vector<int> turns = unwrap_turns(angles);
  for (std::size_t i = 0; i < angles.size(); ++i)
    if (turns[i] != 0) angles[i] += kTwoPi * turns[i];
  return turns;
}

double odd_extended(std::span<const double> x, long i) {
  const long last = static_cast<long>(x.size()) - 1;
  if (last == 0) return x[0];
  double sign = 1, offset = 0;
  while (i < 0 || i > last) {
    offset += sign * 2 * (i < 0 ? x[0] : x[static_cast<std::size_t>(last)]);
    sign = -sign;
    i = i < 0 ? -i : 2 * last - i;
  }
  return offset + sign * x[static_cast<std::size_t>(i)];
}

Eigen::MatrixXd gaussian_smoothed(const Eigen::MatrixXd& curves, double sigma_frames, CurveEnds ends) {
  if (!(sigma_frames > 0) || !std::isfinite(sigma_frames))
    throw std::invalid_argument("Gaussian smoothing: sigma " + std::to_string(sigma_frames) +
                                " samples (expected > 0)");
  if (sigma_frames > (1 << 20))
    throw std::invalid_argument("Gaussian smoothing: sigma " + std::to_string(sigma_frames) +
                                " samples is too wide a kernel (at most 2^20)");
  const int samples = static_cast<int>(curves.rows());
  if (samples < 2) return curves;
  const int radius = static_cast<int>(std::ceil(4 * sigma_frames));
  std::vector<double> kernel(static_cast<std::size_t>(2 * radius + 1));
  double sum = 0;
  for (int k = -radius; k <= radius; ++k)
    sum += kernel[static_cast<std::size_t>(k + radius)] =
        std::exp(-0.5 * k * k / (sigma_frames * sigma_frames));
  for (double& w : kernel) w /= sum;

  std::optional<ParabolaEnds> parabola;
  if (ends == CurveEnds::Parabola) parabola.emplace(curves, radius);
  Eigen::MatrixXd out(curves.rows(), curves.cols());
  for (Eigen::Index c = 0; c < curves.cols(); ++c) {
    const std::span<const double> x(curves.col(c).data(), static_cast<std::size_t>(samples));
    auto at = [&](int f) {
      if (f >= 0 && f < samples) return x[static_cast<std::size_t>(f)];
      if (!parabola) return odd_extended(x, f);
      return f < 0 ? parabola->before(f, c) : parabola->after(samples - 1 - f, c);
    };
    for (int f = 0; f < samples; ++f) {
      double v = 0;
      for (int k = -radius; k <= radius; ++k) v += kernel[static_cast<std::size_t>(k + radius)] * at(f + k);
      out(f, c) = v;
    }
  }
  return out;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace kg::motion
