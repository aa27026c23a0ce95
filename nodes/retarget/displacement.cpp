#include "kg/retarget/displacement.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace kg::retarget {

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
      std::vector<motion::BasisAt> table(static_cast<std::size_t>(frames));
      for (int f = 0; f < frames; ++f)
        table[static_cast<std::size_t>(f)] = motion::bspline_basis(f, frames, k);
      basis_.push_back(std::move(table));
      it = distinct.end() - 1;
    }
    spacing_slot_[c] = static_cast<int>(it - distinct.begin());
    controls_.push_back(motion::bspline_control_count(frames, k));
    offset_.push_back(total_);
    total_ += controls_.back();
  }
}

const motion::BasisAt& DisplacementLayout::basis(int channel, int frame) const {
  return basis_[static_cast<std::size_t>(spacing_slot_[static_cast<std::size_t>(channel)])]
               [static_cast<std::size_t>(frame)];
}

motion::FrameMatrix DisplacementLayout::sample(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  if (x.size() != total_)
    throw std::invalid_argument("displacement map: " + std::to_string(x.size()) +
                                " controls given, layout has " + std::to_string(total_));
  motion::FrameMatrix d(frames_, channel_count());
  for (int c = 0; c < channel_count(); ++c) {
    const double* xc = x.data() + offset(c);
    for (int f = 0; f < frames_; ++f) {
      const motion::BasisAt& b = basis(c, f);
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
      const motion::BasisAt& b = basis(c, f);
      for (int p = 0; p < 4; ++p) {
        rhs[b.first + p] += b.weight[static_cast<std::size_t>(p)] * values(f, c);
        for (int q = 0; q < 4; ++q)
          A(b.first + p, b.first + q) +=
              b.weight[static_cast<std::size_t>(p)] * b.weight[static_cast<std::size_t>(q)];
      }
    }
    x.segment(offset(c), n) = A.ldlt().solve(rhs);
  }
  return x;
}

}  // namespace kg::retarget
