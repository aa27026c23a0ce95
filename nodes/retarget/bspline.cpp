#include "kg/retarget/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace kg::retarget {

namespace {

void check_sizes(int frames, int spacing) {
  if (frames < 1) throw std::invalid_argument("B-spline: " + std::to_string(frames) + " frames (expected >= 1)");
  if (spacing < 1)
    throw std::invalid_argument("B-spline: key spacing " + std::to_string(spacing) + " frames (expected >= 1)");
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

DisplacementLayout::DisplacementLayout(int frames, std::vector<int> spacing)
    : frames_(frames), spacing_(std::move(spacing)) {
  if (frames < 1) throw std::invalid_argument("displacement map: " + std::to_string(frames) + " frames");
  std::vector<int> distinct;
  spacing_slot_.resize(spacing_.size());
  for (std::size_t c = 0; c < spacing_.size(); ++c) {
    const int k = spacing_[c];
    if (k < 1)
      throw std::invalid_argument("displacement map: channel " + std::to_string(c) + " has key spacing " +
                                  std::to_string(k) + " (expected >= 1 frame)");
    auto it = std::find(distinct.begin(), distinct.end(), k);
    if (it == distinct.end()) {
      distinct.push_back(k);
      std::vector<BasisAt> table(static_cast<std::size_t>(frames));
      for (int f = 0; f < frames; ++f) table[static_cast<std::size_t>(f)] = bspline_basis(f, frames, k);
      basis_.push_back(std::move(table));
      it = distinct.end() - 1;
    }
    spacing_slot_[c] = static_cast<int>(it - distinct.begin());
    controls_.push_back(bspline_control_count(frames, k));
    offset_.push_back(total_);
    total_ += controls_.back();
  }
}

const BasisAt& DisplacementLayout::basis(int channel, int frame) const {
  return basis_[static_cast<std::size_t>(spacing_slot_[static_cast<std::size_t>(channel)])]
               [static_cast<std::size_t>(frame)];
}

motion::FrameMatrix DisplacementLayout::sample(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  if (x.size() != total_)
    throw std::invalid_argument("displacement map: " + std::to_string(x.size()) + " controls given, layout has " +
                                std::to_string(total_));
  motion::FrameMatrix d(frames_, channel_count());
  for (int c = 0; c < channel_count(); ++c) {
    const double* xc = x.data() + offset(c);
    for (int f = 0; f < frames_; ++f) {
      const BasisAt& b = basis(c, f);
      const double* p = xc + b.first;
      d(f, c) = b.weight[0] * p[0] + b.weight[1] * p[1] + b.weight[2] * p[2] + b.weight[3] * p[3];
    }
  }
  return d;
}

motion::FrameMatrix DisplacementLayout::apply(const motion::FrameMatrix& m1,
                                              const Eigen::Ref<const Eigen::VectorXd>& x) const {
  if (m1.rows() != frames_ || m1.cols() != channel_count())
    throw std::invalid_argument("displacement map: motion is " + std::to_string(m1.rows()) + " x " +
                                std::to_string(m1.cols()) + ", layout " + std::to_string(frames_) + " x " +
                                std::to_string(channel_count()));
  motion::FrameMatrix m = sample(x);
  m += m1;
  return m;
}

Eigen::VectorXd DisplacementLayout::fit(const motion::FrameMatrix& values, double damping) const {
  if (values.rows() != frames_ || values.cols() != channel_count())
    throw std::invalid_argument("displacement map: fit of a " + std::to_string(values.rows()) + " x " +
                                std::to_string(values.cols()) + " matrix to a layout of " +
                                std::to_string(frames_) + " x " + std::to_string(channel_count()));
  Eigen::VectorXd x(total_);
  for (int c = 0; c < channel_count(); ++c) {
    const int n = control_count(c);
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n) * damping;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
    for (int f = 0; f < frames_; ++f) {
      const BasisAt& b = basis(c, f);
      for (int p = 0; p < 4; ++p) {
        rhs[b.first + p] += b.weight[static_cast<std::size_t>(p)] * values(f, c);
        for (int q = 0; q < 4; ++q)
          A(b.first + p, b.first + q) += b.weight[static_cast<std::size_t>(p)] * b.weight[static_cast<std::size_t>(q)];
      }
    }
    x.segment(offset(c), n) = A.ldlt().solve(rhs);
  }
  return x;
}

}  // namespace kg::retarget
