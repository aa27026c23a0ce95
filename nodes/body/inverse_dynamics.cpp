#include "kg/body/inverse_dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace kg::body {

namespace {

std::string str(int i) {
  return std::to_string(i);
}

void check_frame_size(const BodyModel& body, Eigen::Index size, const char* who, const char* what) {
  if (size != body.skeleton->channel_count())
    throw std::invalid_argument(std::string(who) + ": " + what + " has " + std::to_string(size) +
                                " values, the body's skeleton has " + str(body.skeleton->channel_count()) +
                                " channels");
}

}  // namespace

// The per-call guard of the recursions: what they need to index safely and give finite numbers.
// Cheap enough for every frame; the whole model is checked once per clip by check_body_model
// (body_build.hpp), whose positive-definiteness test would cost more than the recursion.
void check_dynamics_body(const BodyModel& body, const char* who) {
  if (!body.skeleton) throw std::invalid_argument(std::string(who) + ": the body model has no skeleton");
  const motion::Skeleton& s = *body.skeleton;
  if (body.segments.size() != static_cast<std::size_t>(s.joint_count()))
    throw std::invalid_argument(std::string(who) + ": the body model has " +
                                std::to_string(body.segments.size()) + " segments for " +
                                str(s.joint_count()) + " joints (expected one per joint)");
  // Called on every frame: the message is built only on failure.
  for (int j = 0; j < s.joint_count(); ++j) {
    const SegmentInertia& seg = body.segments[static_cast<std::size_t>(j)];
    const char* problem = nullptr;
    const Eigen::Matrix3d& I = seg.inertia;
    if (!std::isfinite(seg.mass) || seg.mass < 0)
      problem = "mass is negative or not finite";
    else if (!seg.com.allFinite())
      problem = "centre of mass is not finite";
    else if (!I.allFinite())
      problem = "inertia is not finite";
    else if (std::abs(I(0, 1) - I(1, 0)) + std::abs(I(0, 2) - I(2, 0)) + std::abs(I(1, 2) - I(2, 1)) >
             1e-9 * std::max(1.0, I.cwiseAbs().maxCoeff()))
      problem = "inertia is not symmetric";
    if (problem)
      throw std::invalid_argument(std::string(who) + ": segment '" + s.joint(j).name + "': " + problem +
                                  " (mass " + std::to_string(seg.mass) + " kg)");
  }
}

// Topology and buffers for body's skeleton (no allocation when they already fit).
void prepare_dynamics(const BodyModel& body, DynamicsWorkspace& ws) {
  DynamicsTopology::build(*body.skeleton, ws.topology);
  ws.kinematics.resize(body.skeleton->joint_count(), body.skeleton->channel_count());
}

void inverse_dynamics(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd, motion::FrameRef qdd,
                      const Eigen::Vector3d& gravity, std::span<const ExternalForce> external,
                      DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> tau) {
  constexpr const char* who = "inverse_dynamics";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  check_frame_size(body, qd.size(), who, "q velocity");
  check_frame_size(body, qdd.size(), who, "q acceleration");
  check_frame_size(body, tau.size(), who, "tau");
  if (!gravity.allFinite()) throw std::invalid_argument("inverse_dynamics: gravity is not finite");
  prepare_dynamics(body, ws);
  compute_frame_kinematics(body, q, ws.kinematics);
  const int joints = body.skeleton->joint_count();
  std::span<const Spatial<double>> ext;
  if (!external.empty()) {
    ws.external.assign(static_cast<std::size_t>(joints), Spatial<double>{});
    for (std::size_t i = 0; i < external.size(); ++i) {
      const ExternalForce& e = external[i];
      if (e.joint < 0 || e.joint >= joints)
        throw std::invalid_argument("inverse_dynamics: external force " + std::to_string(i) +
                                    " acts on joint " + str(e.joint) + " (expected 0.." + str(joints - 1) +
                                    ")");
      if (!e.point.allFinite() || !e.force.allFinite() || !e.torque.allFinite())
        throw std::invalid_argument("inverse_dynamics: external force " + std::to_string(i) +
                                    " is not finite");
      const Eigen::Vector3d r = e.point - ws.kinematics.origin;
      Spatial<double>& f = ws.external[static_cast<std::size_t>(e.joint)];
      f.ang += vec3(r.cross(e.force) + e.torque);
      f.lin += vec3(e.force);
    }
    ext = ws.external;
  }
  const double* v = qd.data();
  const double* a = qdd.data();
  double* out = tau.data();
  rnea_pass(
      ws.topology, ws.kinematics, [v](int c) { return v[c]; }, [a](int c) { return a[c]; }, vec3(gravity), -1,
      1.0, ext, ws.numeric, [out](int c, double t) { out[c] = t; });
}

Eigen::VectorXd inverse_dynamics(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                                 motion::FrameRef qdd, const Eigen::Vector3d& gravity,
                                 std::span<const ExternalForce> external) {
  check_dynamics_body(body, "inverse_dynamics");
  DynamicsWorkspace ws;
  Eigen::VectorXd tau(body.skeleton->channel_count());
  inverse_dynamics(body, q, qd, qdd, gravity, external, ws, tau);
  return tau;
}

void mass_matrix(const BodyModel& body, motion::FrameRef q, DynamicsWorkspace& ws,
                 Eigen::Ref<Eigen::MatrixXd> M) {
  constexpr const char* who = "mass_matrix";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  const int n = body.skeleton->channel_count();
  if (M.rows() != n || M.cols() != n)
    throw std::invalid_argument("mass_matrix: M is " + std::to_string(M.rows()) + " x " +
                                std::to_string(M.cols()) + ", expected " + str(n) + " x " + str(n));
  prepare_dynamics(body, ws);
  compute_frame_kinematics(body, q, ws.kinematics);
  const DynamicsTopology& topo = ws.topology;
  const int joints = static_cast<int>(topo.joints.size());
  ws.composite.assign(ws.kinematics.inertia.begin(), ws.kinematics.inertia.end());
  for (int j = joints - 1; j >= 0; --j) {
    const int parent = topo.joints[static_cast<std::size_t>(j)].parent;
    if (parent >= 0)
      ws.composite[static_cast<std::size_t>(parent)] += ws.composite[static_cast<std::size_t>(j)];
  }
  M.setZero();
  const std::vector<Spatial<double>>& S = ws.kinematics.axis;
  for (int j = 0; j < joints; ++j) {
    const DynamicsTopology::JointInfo& jt = topo.joints[static_cast<std::size_t>(j)];
    for (int k = jt.begin; k < jt.end; ++k) {
      const int c = topo.order[static_cast<std::size_t>(k)];
      // The force the subtree of j needs to accelerate along channel c alone (the bodies between a
      // joint's channels are massless, so every channel of j sees the same composite inertia).
      const Spatial<double> F = ws.composite[static_cast<std::size_t>(j)] * S[static_cast<std::size_t>(c)];
      for (int a = j; a >= 0; a = topo.joints[static_cast<std::size_t>(a)].parent) {
        const DynamicsTopology::JointInfo& at = topo.joints[static_cast<std::size_t>(a)];
        for (int l = at.begin; l < at.end; ++l) {
          const int e = topo.order[static_cast<std::size_t>(l)];
          const double x = dot(S[static_cast<std::size_t>(e)], F);
          M(c, e) = x;
          M(e, c) = x;
        }
      }
    }
  }
}

void bias_forces(const BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                 const Eigen::Vector3d& gravity, DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> bias) {
  constexpr const char* who = "bias_forces";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  check_frame_size(body, qd.size(), who, "q velocity");
  check_frame_size(body, bias.size(), who, "bias");
  if (!gravity.allFinite()) throw std::invalid_argument("bias_forces: gravity is not finite");
  prepare_dynamics(body, ws);
  compute_frame_kinematics(body, q, ws.kinematics);
  const double* v = qd.data();
  double* out = bias.data();
  rnea_pass(
      ws.topology, ws.kinematics, [v](int c) { return v[c]; }, [](int) { return 0.0; }, vec3(gravity), -1,
      1.0, {}, ws.numeric, [out](int c, double t) { out[c] = t; });
}

}  // namespace kg::body
