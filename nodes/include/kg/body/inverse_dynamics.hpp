// Numeric inverse dynamics of a body model (body_model.hpp) at one configuration: the joint torques
// τ = M q̈ + C + G − Jᵀ f by the recursive Newton–Euler algorithm (rnea.hpp), the joint-space mass
// matrix M(q) by the composite rigid body algorithm, and the bias forces C q̇ + G.
//
// Generalised coordinates are the skeleton's channels (skeleton.hpp), each a one-degree-of-freedom
// joint; τ has one entry per channel, newtons for position channels and newton metres for
// rotation ones. τ is what the figure's joints must apply, plus for the root channels the
// residual the environment must supply: the world force along each root position channel's axis
// and the moment about the root joint's origin around each root rotation channel's axis. External
// forces (contacts, pushes) act on the figure and are subtracted. Gravity is a world vector (m/s²,
// +Y up: (0, −9.81, 0) on Earth).
//
//   DynamicsWorkspace ws;                                      // caller-owned, reused
//   Eigen::VectorXd tau(channels);
//   inverse_dynamics(body, q, qd, qdd, body.gravity, {}, ws, tau);
//
// Every function checks its inputs (the body cheaply per call with check_dynamics_body, and whole
// once per clip with check_body_model; sizes) and throws std::invalid_argument naming what is
// wrong. Functions taking a DynamicsWorkspace allocate only when it is new or the skeleton has
// grown.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "kg/body/body_model.hpp"
#include "kg/body/rnea.hpp"
#include "kg/motion/motion.hpp"

namespace kg::body {

// Buffers of the functions below, sized for one skeleton at a time (reusable across skeletons;
// it regrows). Its contents are scratch: nothing in it is meaningful between calls.
struct DynamicsWorkspace {
  DynamicsTopology topology;
  FrameKinematics kinematics;
  RneaBuffers<double, double, double> numeric;
  std::vector<Spatial<double>> external;  // per joint
  std::vector<SpatialInertia> composite;  // per joint
};

// A force the environment applies to one segment.
struct ExternalForce {
  int joint = -1;                                    // the segment it acts on (joint index)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   // where it acts: world, metres
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // world, newtons
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // an additional pure couple: world, newton metres
};

// τ (channel_count) that moves the figure through q (frame values: metres, radians), q̇ and q̈
// (channel_count each, per second and per second²) under `gravity` (world, m/s²) with `external`
// forces acting on it.
void inverse_dynamics(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd, motion::FrameRef qdd,
                      const Eigen::Vector3d& gravity, std::span<const ExternalForce> external,
                      DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> tau);
// The same, allocating its result.
Eigen::VectorXd inverse_dynamics(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                                 motion::FrameRef qdd, const Eigen::Vector3d& gravity,
                                 std::span<const ExternalForce> external = {});

// The joint-space mass matrix M(q) (channel_count x channel_count, symmetric) by the composite
// rigid body algorithm, independently of the recursion above.
void mass_matrix(const BodyModel& body, motion::FrameRef q, DynamicsWorkspace& ws,
                 Eigen::Ref<Eigen::MatrixXd> M);
// C(q, q̇) q̇ + G(q): τ at zero acceleration and no external force (channel_count).
void bias_forces(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                 const Eigen::Vector3d& gravity, DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> bias);

// The per-call guard of the recursions: what they need to index safely and give finite numbers
// (one segment per joint; finite, non-negative masses; finite, symmetric inertias). `who` starts
// the message. Cheap enough for every frame; check_body_model (body_build.hpp) checks the whole
// model once per clip.
void check_dynamics_body(const BodyModel& body, const char* who);

// Sizes `ws`'s topology and buffers for body's skeleton (no allocation when they already fit).
void prepare_dynamics(const BodyModel& body, DynamicsWorkspace& ws);

}  // namespace kg::body
