// Dense banded Cholesky of a symmetric positive definite n x n matrix of half-bandwidth b: the
// linear algebra of the spacetime solver's normal equations (banded, because each B-spline
// control touches only the frames of its four segments).
// Lower band stored by rows: row i holds A(i, i - b .. i), the diagonal last, so the inner
// products run over contiguous memory. Cost n b^2 / 2 multiply-adds, storage n (b + 1).
//
//   BandedCholesky a;
//   a.reset(n, b);
//   a.at(i, j) += v;              // i >= j, i - j <= b
//   if (a.factor()) a.solve(y);   // y: rhs in, solution out
#pragma once

#include <vector>

#include <Eigen/Core>

namespace kg::numerics {

class BandedCholesky {
 public:
  // An n x n zero matrix of half-bandwidth b (0 <= b < n, or n == 0).
  void reset(int n, int b);
  int size() const { return n_; }
  int bandwidth() const { return b_; }
  // Entry (i, j) of the lower band: i >= j, i - j <= bandwidth().
  double& at(int i, int j) { return data_[static_cast<std::size_t>(i) * (b_ + 1) + (j - i + b_)]; }
  // In place A = L L^T; false when A is not positive definite.
  bool factor();
  // After factor(): solves A y = rhs, y holding rhs on entry.
  void solve(Eigen::VectorXd& y) const;

 private:
  int n_ = 0, b_ = 0;
  std::vector<double> data_;
};

}  // namespace kg::numerics
