// The generalised forces along a clip's path as functions of its retiming (McCann et al. 2006
// eq. 5 and 6). A retiming p(t) plays source time p at output time t; with ṗ and p̈ its first two
// derivatives, the forces that follow the path at source frame f are
//
//   τ(ṗ², p̈, g) = velocity·ṗ² + acceleration·p̈ + gravity·g − N λ
//
// where g is the world gravity vector (m/s²) and N λ the generalised forces of the contact
// forces (contacts). velocity = M q'' + C(q, q'), acceleration = M q', gravity = ∂τ/∂g, with
// q', q'' the channels' derivatives with respect to source time (path.hpp). One generalised force
// per channel (body_model.hpp): newtons for position channels, newton metres for rotation ones.
#pragma once

#include <Eigen/Core>

namespace kg::retime {

struct FrameTorques {
  Eigen::VectorXd velocity{};                          // channel_count: coefficient of ṗ²
  Eigen::VectorXd acceleration{};                      // channel_count: coefficient of p̈
  Eigen::Matrix<double, Eigen::Dynamic, 3> gravity{};  // channel_count x 3: coefficients of g

  // τ at a retiming state and gravity, without contact forces.
  Eigen::VectorXd at(double pdot_squared, double pddot, const Eigen::Vector3d& g) const {
    return velocity * pdot_squared + acceleration * pddot + gravity * g;
  }
};

}  // namespace kg::retime
