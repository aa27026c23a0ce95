// Bounded-variable least squares with bounded residuals:
// minimise Σ_i dist(G_i x + e_i, [lo_i, hi_i])² + Σ_j reg_j (x_j − ref_j)²  over xlo <= x <= xhi,
// as Stark & Parker's BVLS over (x, z) with the residuals G x + e − z and lo <= z <= hi: a row
// whose z is free has no residual (it is within its limits), a row whose z sits at a bound is
// violated by its residual. Active set: solve the free variables' least squares, step back to the
// bounds it crosses, free the bound variable whose gradient most wants to move, until none does.
// Used by the retiming's hulls (a frame's least-squares timing when no timing is feasible).
//
//   BoundedLsProblem p{.G = G, .e = e, .lo = lo, .hi = hi, .xlo = xlo, .xhi = xhi, .ref = ref, .reg = reg};
//   BoundedLsResult r = bounded_least_squares(p);   // r.x, r.residual, r.converged
#pragma once

#include <Eigen/Core>

namespace kg::numerics {

struct BoundedLsProblem {
  Eigen::MatrixXd G;  // rows x variables
  Eigen::VectorXd e, lo, hi;
  Eigen::VectorXd xlo, xhi, ref, reg;
};

struct BoundedLsResult {
  Eigen::VectorXd x;
  double residual = 0;  // ‖violations‖ at x
  int iterations = 0;
  bool converged = true;
};

BoundedLsResult bounded_least_squares(const BoundedLsProblem& p);

}  // namespace kg::numerics
