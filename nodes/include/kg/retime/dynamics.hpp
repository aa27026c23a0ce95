// The generalised forces of a clip's path as functions of its retiming (McCann et al. 2006 §3.1,
// eq. 1-6): the "Force" step of the paper's fig. 12, run once per frame before any retiming. The
// numeric inverse dynamics they build on is body::inverse_dynamics (kg/body/inverse_dynamics.hpp).
//
// Generalised coordinates, units and gravity are body::inverse_dynamics' (one entry of τ per
// channel; gravity a world vector, m/s², +Y up).
//
//   DynamicsWorkspace ws;                                      // caller-owned, reused
//   PathDerivatives d = path_derivatives(clip);
//   FrameTorques ft = frame_torques(body, clip, d, f, ws);    // τ(ṗ², p̈, g) at frame f
//   Eigen::VectorXd t = ft.at(pdot * pdot, pddot, body.gravity);
//   MassScaleTorques heavy = frame_torques_mass_scale(body, clip, d, f, femur, ws);
//   Eigen::VectorXd t10 = heavy.at(10.0).at(1, 0, body.gravity);  // femur ten times heavier
//   PathTorques all = path_torques(body, clip, d, femur);     // every frame, for the nodes
//
// Every function checks its inputs (the body cheaply per call, and whole once per clip with
// check_body_model; sizes) and throws std::invalid_argument naming what is wrong. Functions taking a
// DynamicsWorkspace allocate only when it is new or the skeleton has grown; the per-frame work allocates
// nothing.
#pragma once

#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "kg/body/body_model.hpp"
#include "kg/body/inverse_dynamics.hpp"
#include "kg/body/rnea.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/motion.hpp"
#include "kg/retime/path.hpp"
#include "kg/retime/path_torques.hpp"
#include "kg/retime/polynomial.hpp"

namespace kg::retime {

// The variables of the path polynomials (Monomial::variable indices).
enum PathVariable : int {
  kPdot = 0,      // ṗ: source seconds per output second
  kPddot = 1,     // p̈: per output second
  kGravityX = 2,  // gravity's world components, m/s²
  kGravityY = 3,
  kGravityZ = 4,
  kMassScale = 5,  // k: one segment's mass and inertia multiplied by k
};
// Names of the variables above, for Monomial::to_string.
inline constexpr std::array<const char*, 6> kPathVariableNames = {"pdot", "pddot", "gx", "gy", "gz", "k"};

namespace path_terms {
inline constexpr Monomial pdot = Monomial::variable(kPdot);
inline constexpr Monomial pdot2 = Monomial::variable(kPdot, 2);
inline constexpr Monomial pddot = Monomial::variable(kPddot);
inline constexpr Monomial gx = Monomial::variable(kGravityX);
inline constexpr Monomial gy = Monomial::variable(kGravityY);
inline constexpr Monomial gz = Monomial::variable(kGravityZ);
inline constexpr Monomial k = Monomial::variable(kMassScale);
}  // namespace path_terms

// The scalar types of the path recursion: velocities are multiples of ṗ (q̇ = q' ṗ), channel
// accelerations combine ṗ² and p̈ (q̈ = q'' ṗ² + q' p̈), gravity is linear in g, and accelerations
// and forces are linear in ṗ², p̈ and g. With a mass scale, forces gain the same terms times k.
using PathVelocity = Polynomial<SortedBasis<path_terms::pdot>>;
using PathChannelAcceleration = Polynomial<SortedBasis<path_terms::pdot2, path_terms::pddot>>;
using PathGravity = Polynomial<SortedBasis<path_terms::gx, path_terms::gy, path_terms::gz>>;
using PathAcceleration = Polynomial<UnionBasis<PathChannelAcceleration::BasisType, PathGravity::BasisType>>;
using PathMassScale = Polynomial<SortedBasis<path_terms::k>>;
using PathMassForce =
    Polynomial<UnionBasis<PathAcceleration::BasisType,
                          ProductBasis<PathMassScale::BasisType, PathAcceleration::BasisType>>>;

// Buffers of every function below: the numeric recursions' (body::DynamicsWorkspace) and the path
// recursion's, sized for one skeleton at a time (reusable across skeletons; it regrows). Its
// contents are scratch: nothing in it is meaningful between calls.
struct DynamicsWorkspace : body::DynamicsWorkspace {
  body::RneaBuffers<PathVelocity, PathAcceleration, PathAcceleration> path;
  body::RneaBuffers<PathVelocity, PathAcceleration, PathMassForce> path_mass;
};

// τ(ṗ², p̈, g) at source frame `frame` of `clip` (whose skeleton has body's channels), with q', q''
// from `d` = path_derivatives(clip): velocity = M q'' + C(q, q') q', acceleration = M q', gravity =
// ∂τ/∂g (path_torques.hpp). `out`'s storage is reused (no allocation once sized).
void frame_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                   int frame, DynamicsWorkspace& ws, FrameTorques& out);
FrameTorques frame_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                           int frame, DynamicsWorkspace& ws);

// τ when one segment's mass and inertia are multiplied by k: τ(k) = base + (k − 1) change, exactly
// (τ is affine in k). base is frame_torques' answer; change is the scaled segment's own
// contribution (zero on channels that do not carry it: those of other branches).
struct MassScaleTorques {
  FrameTorques base;    // at k = 1
  FrameTorques change;  // ∂τ/∂k
  FrameTorques at(double k) const {
    return {base.velocity + (k - 1) * change.velocity, base.acceleration + (k - 1) * change.acceleration,
            base.gravity + (k - 1) * change.gravity};
  }
};
// `joint`: the segment scaled (0..joint_count-1).
void frame_torques_mass_scale(const body::BodyModel& body, const motion::Motion& clip,
                              const PathDerivatives& d, int frame, int joint, DynamicsWorkspace& ws,
                              MassScaleTorques& out);
MassScaleTorques frame_torques_mass_scale(const body::BodyModel& body, const motion::Motion& clip,
                                          const PathDerivatives& d, int frame, int joint,
                                          DynamicsWorkspace& ws);

// The whole clip, for the nodes: frame_torques of every frame of `clip` (with d =
// path_derivatives(clip)) in frames; with `segment` >= 0 (a joint index) also that segment's name
// and, per frame, the change of τ per unit of its mass scale (frame_torques_mass_scale's change).
// skeleton and fps are the clip's.
PathTorques path_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                         int segment = -1);

}  // namespace kg::retime
