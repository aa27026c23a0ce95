#include "kg/retime/dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "kg/body/body_build.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::retime {

namespace {

std::string str(int i) {
  return std::to_string(i);
}

void check_clip(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d, int frame,
                const char* who) {
  body::check_dynamics_body(body, who);
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
  body::prepare_dynamics(body, ws);
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

void frame_torques(const body::BodyModel& body, const motion::Motion& clip, const PathDerivatives& d,
                   int frame, DynamicsWorkspace& ws, FrameTorques& out) {
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

void frame_torques_mass_scale(const body::BodyModel& body, const motion::Motion& clip,
                              const PathDerivatives& d, int frame, int joint, DynamicsWorkspace& ws,
                              MassScaleTorques& out) {
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
