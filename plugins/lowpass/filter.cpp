#include "filter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "kg/motion/filters.hpp"

namespace kg::lowpass {
namespace {

void check_cutoff(double cutoff_hz, double fps) {
  if (!(fps > 0) || !std::isfinite(fps)) {
    throw std::invalid_argument("frame rate must be positive, got " + std::to_string(fps) + " fps");
  }
  if (!(cutoff_hz > 0) || !std::isfinite(cutoff_hz)) {
    throw std::invalid_argument("cutoff_hz must be positive, got " + std::to_string(cutoff_hz));
  }
  if (cutoff_hz >= 0.5 * fps) {
    throw std::invalid_argument("cutoff_hz " + std::to_string(cutoff_hz) +
                                " must be below the Nyquist frequency " + std::to_string(0.5 * fps) +
                                " Hz (half the motion's " + std::to_string(fps) + " fps)");
  }
}

// `x` with `pad` extended samples before and after, into `padded`.
void pad_odd(std::span<const double> x, int pad, std::vector<double>& padded) {
  const long n = static_cast<long>(x.size());
  padded.resize(static_cast<std::size_t>(n + 2 * pad));
  double* p = padded.data();
  for (long k = 0; k < pad; ++k) {
    p[k] = motion::odd_extended(x, k - pad);
    p[pad + n + k] = motion::odd_extended(x, n + k);
  }
  std::copy(x.begin(), x.end(), p + pad);
}

// One pass through the cascade, in place, each section started in its steady state for a
// constant input equal to data[0] (so a constant passes through untouched).
template <class Index>
void run_cascade(const std::vector<Biquad>& sections, double* data, int n, Index at) {
  for (const Biquad& s : sections) {
    const double gain = (s.b0 + s.b1 + s.b2) / (1 + s.a1 + s.a2);
    const double x0 = data[at(0)];
    double z2 = (s.b2 - s.a2 * gain) * x0;
    double z1 = (s.b1 - s.a1 * gain) * x0 + z2;
    for (int i = 0; i < n; ++i) {
      double& v = data[at(i)];
      const double x = v;
      const double y = s.b0 * x + z1;
      z1 = s.b1 * x - s.a1 * y + z2;
      z2 = s.b2 * x - s.a2 * y;
      v = y;
    }
  }
}

}  // namespace

std::vector<Biquad> butterworth_lowpass(int order, double cutoff_hz, double fps) {
  if (order < 2 || order % 2 != 0) {
    throw std::invalid_argument("Butterworth order must be even and at least 2, got " +
                                std::to_string(order));
  }
  check_cutoff(cutoff_hz, fps);
  // Prewarped: the analog cutoff tan(pi fc / fs) maps back to exactly fc.
  const double k = std::tan(std::numbers::pi * cutoff_hz / fps);
  const double k2 = k * k;
  std::vector<Biquad> sections;
  for (int i = 1; i <= order / 2; ++i) {
    // Pole pair i of the prototype: s^2 + 2 sin((2i - 1) pi / 2N) s + 1.
    const double damping = 2 * std::sin((2 * i - 1) * std::numbers::pi / (2.0 * order));
    const double norm = 1 / (1 + damping * k + k2);
    Biquad s;
    s.b0 = k2 * norm;
    s.b1 = 2 * s.b0;
    s.b2 = s.b0;
    s.a1 = 2 * (k2 - 1) * norm;
    s.a2 = (1 - damping * k + k2) * norm;
    sections.push_back(s);
  }
  return sections;
}

int filtfilt_padding(const std::vector<Biquad>& sections) {
  double radius = 0;
  for (const Biquad& s : sections) {
    const double discriminant = s.a1 * s.a1 - 4 * s.a2;
    const double r = discriminant < 0 ? std::sqrt(s.a2)
                                      : std::max(std::abs(-s.a1 + std::sqrt(discriminant)),
                                                 std::abs(-s.a1 - std::sqrt(discriminant))) /
                                            2;
    radius = std::max(radius, r);
  }
  const int scipy = 3 * (2 * static_cast<int>(sections.size()) + 1);
  constexpr int kMaxPadding = 1 << 22;  // a cutoff ~1e-6 of the frame rate; beyond any real use
  if (radius <= 0) return scipy;
  if (radius >= 1) return kMaxPadding;
  const double decay = std::ceil(std::log(1e-10) / std::log(radius));
  return static_cast<int>(std::clamp(decay, static_cast<double>(scipy), static_cast<double>(kMaxPadding)));
}

void filtfilt(const std::vector<Biquad>& sections, int padding, std::span<double> signal,
              FilterScratch& scratch) {
  const int n = static_cast<int>(signal.size());
  if (n < 2) return;
  const int pad = std::max(padding, 0);
  // Filtering x - x[0] and adding x[0] back is the same linear operation, but keeps a constant
  // signal bit-exact (all zeros stay zeros).
  const double base = signal[0];
  for (double& v : signal) v -= base;
  pad_odd(signal, pad, scratch.padded);
  const int m = static_cast<int>(scratch.padded.size());
  double* p = scratch.padded.data();
  run_cascade(sections, p, m, [](int i) { return i; });
  run_cascade(sections, p, m, [m](int i) { return m - 1 - i; });
  for (int i = 0; i < n; ++i) signal[i] = p[pad + i] + base;
}

double gaussian_sigma_for_cutoff(double cutoff_hz, double fps) {
  check_cutoff(cutoff_hz, fps);
  const double sigma_seconds = std::sqrt(std::numbers::ln2 / 2) / (std::numbers::pi * cutoff_hz);
  return sigma_seconds * fps;
}

void gaussian_smooth(std::span<double> signal, double sigma_frames) {
  if (signal.size() < 2) return;
  // Smoothing x - x[0] and adding x[0] back is the same linear operation, but keeps a constant
  // signal bit-exact (all zeros stay zeros).
  const double base = signal[0];
  Eigen::Map<Eigen::VectorXd> curve(signal.data(), static_cast<Eigen::Index>(signal.size()));
  curve.array() -= base;
  curve = motion::gaussian_smoothed(curve, sigma_frames, motion::CurveEnds::OddReflection);
  curve.array() += base;
}

}  // namespace kg::lowpass
