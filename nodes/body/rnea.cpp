// The configuration-dependent part of the recursive Newton-Euler inverse dynamics (rnea.hpp):
// channel order per joint and one frame's axes and inertias about the reference point.
#include "kg/body/rnea.hpp"

#include <cmath>

#include "kg/motion/rotations.hpp"

namespace kg::body {

void DynamicsTopology::build(const motion::Skeleton& skeleton, DynamicsTopology& out) {
  const int joints = skeleton.joint_count();
  out.joints.resize(static_cast<std::size_t>(joints));
  out.order.clear();
  out.order.reserve(static_cast<std::size_t>(skeleton.channel_count()));
  for (int j = 0; j < joints; ++j) {
    const motion::Joint& jt = skeleton.joint(j);
    JointInfo& info = out.joints[static_cast<std::size_t>(j)];
    info.parent = jt.parent;
    info.begin = static_cast<int>(out.order.size());
    const int n = static_cast<int>(jt.channels.size());
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < n; ++i)
        if (motion::is_rotation(jt.channels[static_cast<std::size_t>(i)].kind) == (pass == 1))
          out.order.push_back(jt.first_channel + i);
    info.end = static_cast<int>(out.order.size());
  }
  out.channel_count = skeleton.channel_count();
}

void compute_frame_kinematics(const BodyModel& body, motion::FrameRef q, FrameKinematics& out) {
  const motion::Skeleton& s = *body.skeleton;
  const int joints = s.joint_count();
  if (out.inertia.size() != static_cast<std::size_t>(joints) ||
      out.axis.size() != static_cast<std::size_t>(s.channel_count()))
    out.resize(joints, s.channel_count());
  const double* values = q.data();
  for (int j = 0; j < joints; ++j) {
    const motion::Joint& jt = s.joint(j);
    const auto uj = static_cast<std::size_t>(j);
    Eigen::Matrix3d Rp;
    Eigen::Vector3d pp;
    if (jt.parent < 0) {
      Rp = s.file_to_world;
      pp.setZero();
    } else {
      const Eigen::Isometry3d& P = out.world[static_cast<std::size_t>(jt.parent)];
      Rp = P.linear();
      pp = P.translation();
    }
    Eigen::Vector3d t = jt.offset;
    bool rotated = false;
    for (std::size_t i = 0; i < jt.channels.size(); ++i) {
      const motion::ChannelKind kind = jt.channels[i].kind;
      if (motion::is_rotation(kind))
        rotated = true;
      else
        t[motion::axis_index(kind)] = values[jt.first_channel + static_cast<int>(i)];
    }
    const Eigen::Vector3d p = Rp * t + pp;
    if (j == 0) out.origin = p;
    const Vec3<double> r = vec3(p - out.origin);
    Eigen::Matrix3d R = Rp;
    if (rotated) {
      const bool plain = motion::is_identity(jt.axis);
      if (!plain) R = Rp * jt.axis;
      for (std::size_t i = 0; i < jt.channels.size(); ++i) {
        const motion::ChannelKind kind = jt.channels[i].kind;
        if (!motion::is_rotation(kind)) continue;
        const int a = motion::axis_index(kind);
        const int c = jt.first_channel + static_cast<int>(i);
        const Vec3<double> w = vec3(R.col(a));
        out.axis[static_cast<std::size_t>(c)] = {w, cross(r, w)};
        const double x = values[c];
        motion::post_rotate(R, a, std::cos(x), std::sin(x));
      }
      if (!plain) R = R * jt.axis.transpose();
    }
    for (std::size_t i = 0; i < jt.channels.size(); ++i) {
      const motion::ChannelKind kind = jt.channels[i].kind;
      if (!motion::is_rotation(kind))
        out.axis[static_cast<std::size_t>(jt.first_channel) + i] = {{},
                                                                    vec3(Rp.col(motion::axis_index(kind)))};
    }
    Eigen::Isometry3d& W = out.world[uj];
    W.linear() = R;
    W.translation() = p;
    W.makeAffine();

    const SegmentInertia& seg = body.segments[uj];
    SpatialInertia& I = out.inertia[uj];
    if (seg.mass == 0 && seg.inertia.isZero(0)) {
      I = SpatialInertia{};
      continue;
    }
    const Eigen::Vector3d c = R * seg.com + (p - out.origin);
    const Eigen::Matrix3d Ic = R * seg.inertia * R.transpose();
    const double m = seg.mass;
    const double cc = c.squaredNorm();
    I.m = m;
    I.h = vec3(m * c);
    I.xx = Ic(0, 0) + m * (cc - c.x() * c.x());
    I.yy = Ic(1, 1) + m * (cc - c.y() * c.y());
    I.zz = Ic(2, 2) + m * (cc - c.z() * c.z());
    I.xy = 0.5 * (Ic(0, 1) + Ic(1, 0)) - m * c.x() * c.y();
    I.xz = 0.5 * (Ic(0, 2) + Ic(2, 0)) - m * c.x() * c.z();
    I.yz = 0.5 * (Ic(1, 2) + Ic(2, 1)) - m * c.y() * c.z();
  }
}

}  // namespace kg::body
