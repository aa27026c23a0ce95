// Bodies whose physics is known in closed form, for the hull and force-model tests: their torque
// coefficients (path_torques.hpp) written by hand, their contacts through the real kinematics.
//
//   PointMass pm = point_mass(2.0);
//   ContactFrame c = touching(pm.skeleton, pose, {{0, {0, 0, 0}}});
//   FrameTorques t = pm.torques({1, 0, 0}, {0, -2, 0});     // q', q''
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "kg/body/body_model.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/path_torques.hpp"

namespace kg::test {

inline std::shared_ptr<motion::Skeleton> skeleton_of(std::vector<motion::Joint> joints) {
  auto sk = std::make_shared<motion::Skeleton>();
  for (motion::Joint& j : joints) sk->add_joint(std::move(j));
  return sk;
}

inline body::BodyModel body_of(std::shared_ptr<const motion::Skeleton> sk, double mu) {
  body::BodyModel body;
  body.skeleton = sk;
  body.segments.resize(static_cast<std::size_t>(sk->joint_count()));
  body.segment_class.resize(static_cast<std::size_t>(sk->joint_count()));
  body.torque_min = Eigen::VectorXd::Zero(sk->channel_count());
  body.torque_max = Eigen::VectorXd::Zero(sk->channel_count());
  body.friction = mu;
  return body;
}

// The contact state of one pose: every listed vertex (joint, local point) touches, one patch each.
inline retime::ContactFrame touching(std::shared_ptr<const motion::Skeleton> sk,
                                     const Eigen::RowVectorXd& pose,
                                     const std::vector<retime::ContactVertex>& vertices) {
  motion::Motion m{sk, motion::FrameMatrix(pose), 30.0, "pose"};
  std::vector<retime::ContactPatch> patches;
  for (std::size_t i = 0; i < vertices.size(); ++i)
    patches.push_back({std::string("v").append(std::to_string(i)), {vertices[i]}});
  return retime::assemble_contacts(m, patches, {std::vector<bool>(vertices.size(), true)}).frames.front();
}

// A mass m at the origin of a root with three position channels (no rotation): τ = m(q'' ṗ² +
// q' p̈) − m g − f.
struct PointMass {
  std::shared_ptr<const motion::Skeleton> skeleton;
  body::BodyModel body;
  double mass = 1;

  retime::FrameTorques torques(const Eigen::Vector3d& qd, const Eigen::Vector3d& qdd) const {
    retime::FrameTorques t;
    t.velocity = mass * qdd;
    t.acceleration = mass * qd;
    t.gravity = -mass * Eigen::Matrix3d::Identity();
    return t;
  }
};

inline PointMass point_mass(double mass, double mu = 0.5) {
  using motion::ChannelKind;
  auto sk = skeleton_of(
      {{.name = "mass",
        .parent = -1,
        .channels = {{ChannelKind::Xposition}, {ChannelKind::Yposition}, {ChannelKind::Zposition}}}});
  PointMass pm{sk, body_of(sk, mu), mass};
  pm.body.segments[0].mass = mass;
  return pm;
}

// The point mass on a massless telescopic leg: the foot (the leg joint's origin) is the body's
// position plus (0, l, 0), l the leg's Yposition channel, actuated within ±leg_force newtons. The
// leg's row is −f_y (it pushes the body up by the floor's vertical force).
struct Leg {
  std::shared_ptr<const motion::Skeleton> skeleton;
  body::BodyModel body;
  double mass = 1;

  // q', q'' of the body (the leg channel's are zero: the leg keeps its length).
  retime::FrameTorques torques(const Eigen::Vector3d& qd, const Eigen::Vector3d& qdd) const {
    retime::FrameTorques t;
    t.velocity = Eigen::VectorXd::Zero(4);
    t.acceleration = Eigen::VectorXd::Zero(4);
    t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(4, 3);
    t.velocity.head<3>() = mass * qdd;
    t.acceleration.head<3>() = mass * qd;
    t.gravity.topRows<3>() = -mass * Eigen::Matrix3d::Identity();
    return t;
  }
  Eigen::RowVectorXd pose() const { return (Eigen::RowVectorXd(4) << 0, 1, 0, -1).finished(); }
};

inline Leg leg(double mass, double leg_force, double mu = 0.5) {
  using motion::ChannelKind;
  auto sk = skeleton_of(
      {{.name = "body",
        .parent = -1,
        .channels = {{ChannelKind::Xposition}, {ChannelKind::Yposition}, {ChannelKind::Zposition}}},
       {.name = "leg", .parent = 0, .offset = {0, -1, 0}, .channels = {{ChannelKind::Yposition}}}});
  Leg l{sk, body_of(sk, mu), mass};
  l.body.segments[0].mass = mass;
  l.body.torque_min[3] = -leg_force;
  l.body.torque_max[3] = leg_force;
  return l;
}

// A rigid box turning about the world Z axis through its centre of mass (the root's origin):
// channels X, Y, Z position and Z rotation; mass m, moment of inertia I about Z. No Coriolis
// term: the axis is fixed. τ = (m c'', I θ'') ṗ² + (m c', I θ') p̈ − (m g, 0) − Jᵀ f.
struct PlanarBox {
  std::shared_ptr<const motion::Skeleton> skeleton;
  body::BodyModel body;
  double mass = 1, inertia = 1;

  retime::FrameTorques torques(const Eigen::Vector4d& qd, const Eigen::Vector4d& qdd) const {
    retime::FrameTorques t;
    t.velocity = (Eigen::Vector4d() << mass * qdd.head<3>(), inertia * qdd[3]).finished();
    t.acceleration = (Eigen::Vector4d() << mass * qd.head<3>(), inertia * qd[3]).finished();
    t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(4, 3);
    t.gravity.topRows<3>() = -mass * Eigen::Matrix3d::Identity();
    return t;
  }
};

inline PlanarBox planar_box(double mass, double inertia, double mu = 0.5) {
  using motion::ChannelKind;
  auto sk = skeleton_of({{.name = "box",
                          .parent = -1,
                          .channels = {{ChannelKind::Xposition},
                                       {ChannelKind::Yposition},
                                       {ChannelKind::Zposition},
                                       {ChannelKind::Zrotation}}}});
  PlanarBox b{sk, body_of(sk, mu), mass, inertia};
  b.body.segments[0].mass = mass;
  b.body.segments[0].inertia(2, 2) = inertia;
  return b;
}

}  // namespace kg::test
