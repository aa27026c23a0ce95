#include "kg/retime/dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "kg/motion/rotations.hpp"
#include "kg/body/body_build.hpp"

namespace kg::retime {

namespace {

void check_dynamics_body(const body::BodyModel& body, const char* who);  // below


std::string str(int i) {
  return std::to_string(i);
}

void check_frame_size(const body::BodyModel& body, Eigen::Index size, const char* who, const char* what) {
  if (size != body.skeleton->channel_count())
    throw std::invalid_argument(std::string(who) + ": " + what + " has " + std::to_string(size) +
                                " values, the body's skeleton has " + str(body.skeleton->channel_count()) +
                                " channels");
}

// Topology and buffers for body's skeleton (no allocation when they already fit).
void prepare(const body::BodyModel& body, DynamicsWorkspace& ws) {
  body::DynamicsTopology::build(*body.skeleton, ws.topology);
  ws.kinematics.resize(body.skeleton->joint_count(), body.skeleton->channel_count());
}

void check_clip(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d, int frame,
                const char* who) {
  check_dynamics_body(body, who);
  if (!clip.skeleton)
    throw std::invalid_argument(std::string(who) + ": clip '" + clip.name + "' has no skeleton");
  const motion::Skeleton& s = *body.skeleton;
  if (clip.skeleton->joint_count() != s.joint_count() || clip.skeleton->channel_count() != s.channel_count())
    throw std::invalid_argument(std::string(who) + ": clip '" + clip.name + "' has " +
                                str(clip.skeleton->joint_count()) + " joints and " +
                                str(clip.skeleton->channel_count()) + " channels, the body model " +
                                str(s.joint_count()) + " and " + str(s.channel_count()));
  if (clip.values.cols() != s.channel_count())
    throw std::invalid_argument(std::string(who) + ": clip '" + clip.name + "' has " +
                                std::to_string(clip.values.cols()) + " values per frame, expected " +
                                str(s.channel_count()));
  const auto frames = clip.values.rows();
  if (d.first.rows() != frames || d.first.cols() != s.channel_count() || d.second.rows() != frames ||
      d.second.cols() != s.channel_count())
    throw std::invalid_argument(
        std::string(who) + ": path derivatives are " + std::to_string(d.first.rows()) + " x " +
        std::to_string(d.first.cols()) + " and " + std::to_string(d.second.rows()) + " x " +
        std::to_string(d.second.cols()) + ", clip '" + clip.name + "' is " + std::to_string(frames) + " x " +
        str(s.channel_count()) + " (expected path_derivatives(clip))");
  if (frame < 0 || frame >= frames)
    throw std::invalid_argument(std::string(who) + ": frame " + str(frame) + " out of range (clip '" +
                                clip.name + "' has " + std::to_string(frames) + " frames)");
}

void resize(FrameTorques& t, int channels) {
  t.velocity.resize(channels);
  t.acceleration.resize(channels);
  t.gravity.resize(channels, 3);
}

const body::Vec3<PathGravity> kPathGravity{PathGravity::term<path_terms::gx>(1.0),
                                     PathGravity::term<path_terms::gy>(1.0),
                                     PathGravity::term<path_terms::gz>(1.0)};

// The path recursion for one frame: q̇ = q' ṗ, q̈ = q'' ṗ² + q' p̈, symbolic gravity.
template <class F, class K, class Tau>
void path_pass(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d, int frame,
               int scaled_joint, const K& scale, DynamicsWorkspace& ws,
               body::RneaBuffers<PathVelocity, PathAcceleration, F>& buf, Tau&& tau) {
  prepare(body, ws);
  body::compute_frame_kinematics(body, clip.values.row(frame), ws.kinematics);
  const double* q1 = d.first.row(frame).data();
  const double* q2 = d.second.row(frame).data();
  body::rnea_pass(
      ws.topology, ws.kinematics, [&](int c) { return PathVelocity::term<path_terms::pdot>(q1[c]); },
      [&](int c) {
        PathChannelAcceleration a = PathChannelAcceleration::term<path_terms::pdot2>(q2[c]);
        a += PathChannelAcceleration::term<path_terms::pddot>(q1[c]);
        return a;
      },
      kPathGravity, scaled_joint, scale, {}, buf, tau);
}

}  // namespace

namespace {

// The per-call guard of the recursions: what they need to index safely and give finite numbers.
// Cheap enough for every frame; the whole model is checked once per clip by check_body_model
// (body_build.hpp), whose positive-definiteness test would cost more than the recursion.
void check_dynamics_body(const body::BodyModel& body, const char* who) {
  if (!body.skeleton) throw std::invalid_argument(std::string(who) + ": the body model has no skeleton");
  const motion::Skeleton& s = *body.skeleton;
  if (body.segments.size() != static_cast<std::size_t>(s.joint_count()))
    throw std::invalid_argument(std::string(who) + ": the body model has " +
                                std::to_string(body.segments.size()) + " segments for " +
                                str(s.joint_count()) + " joints (expected one per joint)");
  // Called on every frame: the message is built only on failure.
  for (int j = 0; j < s.joint_count(); ++j) {
    const body::SegmentInertia& seg = body.segments[static_cast<std::size_t>(j)];
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

}  // namespace

void inverse_dynamics(const body::BodyModel& body, motion::FrameRef q, motion::FrameRef qd, motion::FrameRef qdd,
                      const Eigen::Vector3d& gravity, std::span<const ExternalForce> external,
                      DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> tau) {
  constexpr const char* who = "inverse_dynamics";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  check_frame_size(body, qd.size(), who, "q velocity");
  check_frame_size(body, qdd.size(), who, "q acceleration");
  check_frame_size(body, tau.size(), who, "tau");
  if (!gravity.allFinite()) throw std::invalid_argument("inverse_dynamics: gravity is not finite");
  prepare(body, ws);
  body::compute_frame_kinematics(body, q, ws.kinematics);
  const int joints = body.skeleton->joint_count();
  std::span<const body::Spatial<double>> ext;
  if (!external.empty()) {
    ws.external.assign(static_cast<std::size_t>(joints), body::Spatial<double>{});
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
      body::Spatial<double>& f = ws.external[static_cast<std::size_t>(e.joint)];
      f.ang += body::vec3(r.cross(e.force) + e.torque);
      f.lin += body::vec3(e.force);
    }
    ext = ws.external;
  }
  const double* v = qd.data();
  const double* a = qdd.data();
  double* out = tau.data();
  body::rnea_pass(
      ws.topology, ws.kinematics, [v](int c) { return v[c]; }, [a](int c) { return a[c]; }, body::vec3(gravity), -1,
      1.0, ext, ws.numeric, [out](int c, double t) { out[c] = t; });
}

Eigen::VectorXd inverse_dynamics(const body::BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                                 motion::FrameRef qdd, const Eigen::Vector3d& gravity,
                                 std::span<const ExternalForce> external) {
  check_dynamics_body(body, "inverse_dynamics");
  DynamicsWorkspace ws;
  Eigen::VectorXd tau(body.skeleton->channel_count());
  inverse_dynamics(body, q, qd, qdd, gravity, external, ws, tau);
  return tau;
}

void mass_matrix(const body::BodyModel& body, motion::FrameRef q, DynamicsWorkspace& ws,
                 Eigen::Ref<Eigen::MatrixXd> M) {
  constexpr const char* who = "mass_matrix";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  const int n = body.skeleton->channel_count();
  if (M.rows() != n || M.cols() != n)
    throw std::invalid_argument("mass_matrix: M is " + std::to_string(M.rows()) + " x " +
                                std::to_string(M.cols()) + ", expected " + str(n) + " x " + str(n));
  prepare(body, ws);
  body::compute_frame_kinematics(body, q, ws.kinematics);
  const body::DynamicsTopology& topo = ws.topology;
  const int joints = static_cast<int>(topo.joints.size());
  ws.composite.assign(ws.kinematics.inertia.begin(), ws.kinematics.inertia.end());
  for (int j = joints - 1; j >= 0; --j) {
    const int parent = topo.joints[static_cast<std::size_t>(j)].parent;
    if (parent >= 0)
      ws.composite[static_cast<std::size_t>(parent)] += ws.composite[static_cast<std::size_t>(j)];
  }
  M.setZero();
  const std::vector<body::Spatial<double>>& S = ws.kinematics.axis;
  for (int j = 0; j < joints; ++j) {
    const body::DynamicsTopology::JointInfo& jt = topo.joints[static_cast<std::size_t>(j)];
    for (int k = jt.begin; k < jt.end; ++k) {
      const int c = topo.order[static_cast<std::size_t>(k)];
      // The force the subtree of j needs to accelerate along channel c alone (the bodies between a
      // joint's channels are massless, so every channel of j sees the same composite inertia).
      const body::Spatial<double> F = ws.composite[static_cast<std::size_t>(j)] * S[static_cast<std::size_t>(c)];
      for (int a = j; a >= 0; a = topo.joints[static_cast<std::size_t>(a)].parent) {
        const body::DynamicsTopology::JointInfo& at = topo.joints[static_cast<std::size_t>(a)];
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

void bias_forces(const body::BodyModel& body, motion::FrameRef q, motion::FrameRef qd,
                 const Eigen::Vector3d& gravity, DynamicsWorkspace& ws, Eigen::Ref<Eigen::VectorXd> bias) {
  constexpr const char* who = "bias_forces";
  check_dynamics_body(body, who);
  check_frame_size(body, q.size(), who, "q");
  check_frame_size(body, qd.size(), who, "q velocity");
  check_frame_size(body, bias.size(), who, "bias");
  if (!gravity.allFinite()) throw std::invalid_argument("bias_forces: gravity is not finite");
  prepare(body, ws);
  body::compute_frame_kinematics(body, q, ws.kinematics);
  const double* v = qd.data();
  double* out = bias.data();
  body::rnea_pass(
      ws.topology, ws.kinematics, [v](int c) { return v[c]; }, [](int) { return 0.0; }, body::vec3(gravity), -1,
      1.0, {}, ws.numeric, [out](int c, double t) { out[c] = t; });
}

void frame_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d, int frame,
                   DynamicsWorkspace& ws, FrameTorques& out) {
  check_clip(body, clip, d, frame, "frame_torques");
  resize(out, body.skeleton->channel_count());
  using namespace path_terms;
  path_pass(body, clip, d, frame, -1, 1.0, ws, ws.path, [&out](int c, const PathAcceleration& t) {
    out.velocity[c] = t.coefficient<pdot2>();
    out.acceleration[c] = t.coefficient<pddot>();
    out.gravity(c, 0) = t.coefficient<gx>();
    out.gravity(c, 1) = t.coefficient<gy>();
    out.gravity(c, 2) = t.coefficient<gz>();
  });
}

FrameTorques frame_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                           int frame, DynamicsWorkspace& ws) {
  FrameTorques out;
  frame_torques(body, clip, d, frame, ws, out);
  return out;
}

void frame_torques_mass_scale(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                              int frame, int joint, DynamicsWorkspace& ws, MassScaleTorques& out) {
  check_clip(body, clip, d, frame, "frame_torques_mass_scale");
  if (joint < 0 || joint >= body.skeleton->joint_count())
    throw std::invalid_argument("frame_torques_mass_scale: joint " + str(joint) +
                                " out of range (expected 0.." + str(body.skeleton->joint_count() - 1) + ")");
  const int n = body.skeleton->channel_count();
  resize(out.base, n);
  resize(out.change, n);
  using namespace path_terms;
  path_pass(body, clip, d, frame, joint, PathMassScale::term<k>(1.0), ws, ws.path_mass,
            [&out](int c, const PathMassForce& t) {
              const double kv = t.coefficient<k * pdot2>(), ka = t.coefficient<k * pddot>();
              const double kx = t.coefficient<k * gx>(), ky = t.coefficient<k * gy>(),
                           kz = t.coefficient<k * gz>();
              out.change.velocity[c] = kv;
              out.change.acceleration[c] = ka;
              out.change.gravity(c, 0) = kx;
              out.change.gravity(c, 1) = ky;
              out.change.gravity(c, 2) = kz;
              out.base.velocity[c] = t.coefficient<pdot2>() + kv;
              out.base.acceleration[c] = t.coefficient<pddot>() + ka;
              out.base.gravity(c, 0) = t.coefficient<gx>() + kx;
              out.base.gravity(c, 1) = t.coefficient<gy>() + ky;
              out.base.gravity(c, 2) = t.coefficient<gz>() + kz;
            });
}

MassScaleTorques frame_torques_mass_scale(const body::BodyModel& body, const motion::Motion& clip,
                                          const PathDerivatives& d, int frame, int joint,
                                          DynamicsWorkspace& ws) {
  MassScaleTorques out;
  frame_torques_mass_scale(body, clip, d, frame, joint, ws, out);
  return out;
}

PathTorques path_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                         int segment) {
  body::check_body_model(body, "path_torques");
  check_dynamics_body(body, "path_torques");
  if (segment < -1 || segment >= body.skeleton->joint_count())
    throw std::invalid_argument("path_torques: segment " + str(segment) +
                                " out of range (expected -1 for none or 0.." +
                                str(body.skeleton->joint_count() - 1) + ")");
  PathTorques out;
  out.skeleton = clip.skeleton;
  out.fps = clip.fps;
  const auto frames = static_cast<std::size_t>(clip.frame_count());
  out.frames.resize(frames);
  DynamicsWorkspace ws;
  if (segment < 0) {
    for (std::size_t f = 0; f < frames; ++f)
      frame_torques(body, clip, d, static_cast<int>(f), ws, out.frames[f]);
    return out;
  }
  out.segment = body.skeleton->joint(segment).name;
  out.segment_change.resize(frames);
  MassScaleTorques m;
  for (std::size_t f = 0; f < frames; ++f) {
    frame_torques_mass_scale(body, clip, d, static_cast<int>(f), segment, ws, m);
    out.frames[f] = m.base;
    out.segment_change[f] = m.change;
  }
  return out;
}

}  // namespace kg::retime
