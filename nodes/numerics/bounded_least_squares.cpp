#include "kg/numerics/bounded_least_squares.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

namespace kg::numerics {

BoundedLsResult bounded_least_squares(const BoundedLsProblem& p) {
  const Eigen::Index n = p.G.cols(), m = p.G.rows();
  enum State : char { Free, Lower, Upper };
  BoundedLsResult r;
  Eigen::VectorXd x = p.ref.cwiseMax(p.xlo).cwiseMin(p.xhi);
  std::vector<State> xs(static_cast<std::size_t>(n)), zs(static_cast<std::size_t>(m));
  for (Eigen::Index j = 0; j < n; ++j)
    xs[static_cast<std::size_t>(j)] = x[j] <= p.xlo[j] ? Lower : x[j] >= p.xhi[j] ? Upper : Free;
  Eigen::VectorXd z = p.G * x + p.e;
  for (Eigen::Index i = 0; i < m; ++i) {
    State& s = zs[static_cast<std::size_t>(i)];
    s = p.lo[i] == p.hi[i] || z[i] <= p.lo[i] ? Lower : z[i] >= p.hi[i] ? Upper : Free;
    z[i] = std::clamp(z[i], p.lo[i], p.hi[i]);
  }
  const double scale_g = std::max(1.0, p.G.cwiseAbs().maxCoeff());
  double scale_e = 1 + p.e.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < m; ++i)
    for (double b : {p.lo[i], p.hi[i]})
      if (std::isfinite(b)) scale_e = std::max(scale_e, std::abs(b));
  const double tol = 1e-10 * scale_g * scale_e;
  const double step_tol = 1e-12;

  std::vector<Eigen::Index> free_x, bound_rows;
  Eigen::MatrixXd H;
  Eigen::VectorXd rhs, candidate(n), zc(m);
  // The free variables' unconstrained minimiser (bound ones kept), and the free z's (= G x + e).
  auto solve_free = [&]() {
    free_x.clear();
    bound_rows.clear();
    for (Eigen::Index j = 0; j < n; ++j)
      if (xs[static_cast<std::size_t>(j)] == Free) free_x.push_back(j);
    for (Eigen::Index i = 0; i < m; ++i)
      if (zs[static_cast<std::size_t>(i)] != Free) bound_rows.push_back(i);
    const Eigen::Index f = static_cast<Eigen::Index>(free_x.size());
    candidate = x;
    if (f > 0) {
      H.setZero(f, f);
      rhs.setZero(f);
      for (Eigen::Index i : bound_rows) {
        double target = z[i] - p.e[i];
        for (Eigen::Index j = 0; j < n; ++j)
          if (xs[static_cast<std::size_t>(j)] != Free) target -= p.G(i, j) * x[j];
        for (Eigen::Index a = 0; a < f; ++a) {
          const double ga = p.G(i, free_x[static_cast<std::size_t>(a)]);
          if (ga == 0) continue;
          rhs[a] += ga * target;
          for (Eigen::Index b = 0; b < f; ++b) H(a, b) += ga * p.G(i, free_x[static_cast<std::size_t>(b)]);
        }
      }
      for (Eigen::Index a = 0; a < f; ++a) {
        const Eigen::Index j = free_x[static_cast<std::size_t>(a)];
        H(a, a) += p.reg[j];
        rhs[a] += p.reg[j] * p.ref[j];
      }
      const Eigen::VectorXd sol = H.ldlt().solve(rhs);
      for (Eigen::Index a = 0; a < f; ++a) candidate[free_x[static_cast<std::size_t>(a)]] = sol[a];
    }
    zc = z;
    const Eigen::VectorXd tau = p.G * candidate + p.e;
    for (Eigen::Index i = 0; i < m; ++i)
      if (zs[static_cast<std::size_t>(i)] == Free) zc[i] = tau[i];
  };
  // Moves towards the free minimiser, stopping at the first bound crossed (which then binds),
  // until the minimiser is within bounds.
  auto settle = [&]() {
    for (int guard = 0; guard < 4 * static_cast<int>(n + m) + 8; ++guard) {
      solve_free();
      double alpha = 1;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (xs[static_cast<std::size_t>(j)] != Free) continue;
        if (candidate[j] < p.xlo[j]) alpha = std::min(alpha, (x[j] - p.xlo[j]) / (x[j] - candidate[j]));
        if (candidate[j] > p.xhi[j]) alpha = std::min(alpha, (p.xhi[j] - x[j]) / (candidate[j] - x[j]));
      }
      for (Eigen::Index i = 0; i < m; ++i) {
        if (zs[static_cast<std::size_t>(i)] != Free) continue;
        if (zc[i] < p.lo[i]) alpha = std::min(alpha, (z[i] - p.lo[i]) / (z[i] - zc[i]));
        if (zc[i] > p.hi[i]) alpha = std::min(alpha, (p.hi[i] - z[i]) / (zc[i] - z[i]));
      }
      alpha = std::clamp(alpha, 0.0, 1.0);
      x += alpha * (candidate - x);
      z += alpha * (zc - z);
      if (alpha >= 1) return;
      for (Eigen::Index j = 0; j < n; ++j) {
        State& s = xs[static_cast<std::size_t>(j)];
        if (s != Free) continue;
        const double span = std::max(1.0, std::abs(x[j]));
        if (x[j] <= p.xlo[j] + step_tol * span)
          s = Lower, x[j] = p.xlo[j];
        else if (x[j] >= p.xhi[j] - step_tol * span)
          s = Upper, x[j] = p.xhi[j];
      }
      for (Eigen::Index i = 0; i < m; ++i) {
        State& s = zs[static_cast<std::size_t>(i)];
        if (s != Free) continue;
        const double span = std::max(1.0, std::abs(z[i]));
        if (z[i] <= p.lo[i] + step_tol * span)
          s = Lower, z[i] = p.lo[i];
        else if (z[i] >= p.hi[i] - step_tol * span)
          s = Upper, z[i] = p.hi[i];
      }
    }
  };

  settle();
  const int max_outer = 4 * static_cast<int>(n + m) + 20;
  Eigen::VectorXd residual(m), grad(n);
  auto objective = [&]() {
    return 0.5 * (p.G * x + p.e - z).squaredNorm() +
           0.5 * (p.reg.cwiseProduct((x - p.ref).cwiseAbs2())).sum();
  };
  // A variable freed without lowering the objective (rounding sent it straight back to its
  // bound) is not freed again until something else moves: no cycling.
  std::vector<Eigen::Index> stuck;
  for (r.iterations = 0; r.iterations < max_outer; ++r.iterations) {
    residual = p.G * x + p.e - z;
    grad = p.G.transpose() * residual + p.reg.cwiseProduct(x - p.ref);
    auto allowed = [&](Eigen::Index v) { return std::find(stuck.begin(), stuck.end(), v) == stuck.end(); };
    // The bound variable whose gradient most wants it to leave its bound.
    double worst = tol;
    Eigen::Index pick = -1;
    for (Eigen::Index j = 0; j < n; ++j) {
      const State s = xs[static_cast<std::size_t>(j)];
      const double want = s == Lower ? -grad[j] : s == Upper ? grad[j] : 0.0;
      if (want > worst && allowed(j)) worst = want, pick = j;
    }
    for (Eigen::Index i = 0; i < m; ++i) {
      const State s = zs[static_cast<std::size_t>(i)];
      if (s == Free || p.lo[i] == p.hi[i]) continue;
      const double want = s == Lower ? residual[i] : -residual[i];  // d/dz = −residual
      if (want > worst && allowed(n + i)) worst = want, pick = n + i;
    }
    if (pick < 0) break;
    if (pick < n)
      xs[static_cast<std::size_t>(pick)] = Free;
    else
      zs[static_cast<std::size_t>(pick - n)] = Free;
    const double before = objective();
    settle();
    if (objective() < before - 1e-14 * (1 + before))
      stuck.clear();
    else
      stuck.push_back(pick);
  }
  r.converged = r.iterations < max_outer;
  const Eigen::VectorXd tau = p.G * x + p.e;
  double sum = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    const double v = tau[i] < p.lo[i] ? p.lo[i] - tau[i] : tau[i] > p.hi[i] ? tau[i] - p.hi[i] : 0.0;
    sum += v * v;
  }
  r.residual = std::sqrt(sum);
  r.x = std::move(x);
  return r;
}

}  // namespace kg::numerics
