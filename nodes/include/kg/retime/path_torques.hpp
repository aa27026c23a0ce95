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
//
// PathTorques holds them for a whole clip, and how they change with one segment's mass (τ is
// affine in a segment's mass scale k: its mass and inertia times k), so the paper's physical
// edits (§4.2: gravity, a heavier limb) need no inverse dynamics again:
//   τ(k, g) = frames[f].at(...) + (k − 1) · segment_change[f].at(...).
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/skeleton.hpp"

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

struct PathTorques {
  std::shared_ptr<const motion::Skeleton> skeleton;  // shared, immutable
  double fps = 30;                                   // the clip's frame rate
  std::vector<FrameTorques> frames{};                // per frame, the body as modelled (k = 1)
  std::string segment;                               // joint whose mass may be scaled; "" for none
  std::vector<FrameTorques> segment_change{};        // per frame, per unit of k; empty without segment

  int frame_count() const { return static_cast<int>(frames.size()); }
  // Frame f's coefficients with the segment's mass scaled by k (k = 1: frames[f]). Throws
  // std::invalid_argument for k != 1 without a segment.
  FrameTorques edited(int frame, double mass_scale) const {
    const FrameTorques& base = frames.at(static_cast<std::size_t>(frame));
    if (mass_scale == 1) return base;
    if (segment_change.empty())
      throw std::invalid_argument(
          "path torques: a mass scale needs the segment it scales (none was modelled)");
    const FrameTorques& change = segment_change.at(static_cast<std::size_t>(frame));
    const double d = mass_scale - 1;
    return {base.velocity + d * change.velocity, base.acceleration + d * change.acceleration,
            base.gravity + d * change.gravity};
  }
};

}  // namespace kg::retime
