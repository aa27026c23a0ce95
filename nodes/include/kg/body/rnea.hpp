// Featherstone's recursive Newton-Euler inverse dynamics (RNEA) for a floating-base figure, templated
// on its scalar types so the same code gives numbers (double) or the coefficients of the forces as
// polynomials in the retiming's ṗ², p̈, gravity and a mass scale (polynomial.hpp, dynamics.hpp).
// Most callers want dynamics.hpp; this header is for those who bring their own scalar types.
//
// Model (skeleton.hpp, body_model.hpp): every channel is a one-degree-of-freedom joint. A joint's
// position channels slide along its parent frame's axes, then its rotation channels turn, in the
// order listed, about the axes of the ASF `axis` frame carried by the previous ones; the bodies
// between one channel and the next are massless, the last carries the joint's segment.
//
// Formulation: spatial vectors (angular part first) in world axes about one reference point per
// frame, the world position of joint 0's origin (a root). With every quantity about one point, the
// recursion needs no coordinate transform between bodies: a child's velocity is its parent's plus
// its channels' world axes times their rates, forces of children just add up, and the derivative
// of a channel's axis is v × S with v the velocity of the body carrying it. Configuration-dependent
// quantities (axes, inertias about the reference point) are computed once per frame in double
// (compute_frame_kinematics); only velocities, accelerations and forces take the scalar type, and
// they are multiplied by doubles almost everywhere. Compared with Featherstone's body-frame
// recursion (one 6D transform per body and per quantity), this costs one rotation of each inertia
// per frame and nothing per scalar coefficient, which matters when a scalar is five or ten doubles.
// Taking the reference point at the figure rather than at the world origin keeps the parallel-axis
// terms (m |c|²) small when a clip walks far from the origin.
//
// Gravity enters as Featherstone's fictitious base acceleration a₀ = (0, −g), so τ includes
// the forces that hold the figure up against gravity.
//
//   DynamicsTopology topo = DynamicsTopology::of(*body.skeleton);
//   FrameKinematics kin;
//   compute_frame_kinematics(body, q, kin);
//   RneaBuffers<double, double, double> buf;
//   rnea_pass(topo, kin, [&](int c) { return qd[c]; }, [&](int c) { return qdd[c]; },
//             Vec3<double>{0, -9.81, 0}, -1, 1.0, {}, buf, [&](int c, double t) { tau[c] = t; });
#pragma once

#include <span>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>

#include "kg/body/body_model.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::body {

// A 3-vector of any scalar (double or Polynomial).
template <class T>
struct Vec3 {
  T x{}, y{}, z{};

  // From a vector of a narrower scalar (a polynomial over a sub-basis).
  template <class U>
  Vec3& operator=(const Vec3<U>& o) {
    x = o.x;
    y = o.y;
    z = o.z;
    return *this;
  }
};

template <class A, class B>
inline auto operator+(const Vec3<A>& a, const Vec3<B>& b) {
  return Vec3<decltype(a.x + b.x)>{a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class A, class B>
inline auto operator-(const Vec3<A>& a, const Vec3<B>& b) {
  return Vec3<decltype(a.x - b.x)>{a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class A, class B>
inline Vec3<A>& operator+=(Vec3<A>& a, const Vec3<B>& b) {
  a.x += b.x;
  a.y += b.y;
  a.z += b.z;
  return a;
}
template <class A, class B>
inline Vec3<A>& operator-=(Vec3<A>& a, const Vec3<B>& b) {
  a.x -= b.x;
  a.y -= b.y;
  a.z -= b.z;
  return a;
}
// s * v, for a scalar s and a vector v of any scalar types.
template <class S, class T>
inline auto scaled(const S& s, const Vec3<T>& v) {
  return Vec3<decltype(s * v.x)>{s * v.x, s * v.y, s * v.z};
}
template <class A, class B>
inline auto cross(const Vec3<A>& a, const Vec3<B>& b) {
  return Vec3<decltype(a.y * b.z - a.z * b.y)>{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z,
                                               a.x * b.y - a.y * b.x};
}
template <class A, class B>
inline auto dot(const Vec3<A>& a, const Vec3<B>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3<double> vec3(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// A spatial motion (angular velocity, velocity of the body point at the reference point) or force
// (moment about the reference point, force) vector.
template <class T>
struct Spatial {
  Vec3<T> ang{}, lin{};

  template <class U>
  Spatial& operator=(const Spatial<U>& o) {
    ang = o.ang;
    lin = o.lin;
    return *this;
  }
};

template <class A, class B>
inline Spatial<A>& operator+=(Spatial<A>& a, const Spatial<B>& b) {
  a.ang += b.ang;
  a.lin += b.lin;
  return a;
}
template <class A, class B>
inline Spatial<A>& operator-=(Spatial<A>& a, const Spatial<B>& b) {
  a.ang -= b.ang;
  a.lin -= b.lin;
  return a;
}
template <class A, class B>
inline auto operator+(const Spatial<A>& a, const Spatial<B>& b) {
  using T = decltype(a.ang.x + b.ang.x);
  return Spatial<T>{a.ang + b.ang, a.lin + b.lin};
}
template <class S, class T>
inline auto scaled(const S& s, const Spatial<T>& v) {
  using R = decltype(s * v.ang.x);
  return Spatial<R>{scaled(s, v.ang), scaled(s, v.lin)};
}
// Motion cross product a ×m b (the rate of change of b carried by a body moving with a).
template <class A, class B>
inline auto cross_motion(const Spatial<A>& a, const Spatial<B>& b) {
  using T = decltype(a.ang.x * b.ang.x - a.ang.x * b.ang.x);
  return Spatial<T>{cross(a.ang, b.ang), cross(a.ang, b.lin) + cross(a.lin, b.ang)};
}
// Force cross product a ×f f.
template <class A, class B>
inline auto cross_force(const Spatial<A>& a, const Spatial<B>& f) {
  using T = decltype(a.ang.x * f.ang.x - a.ang.x * f.ang.x);
  return Spatial<T>{cross(a.ang, f.ang) + cross(a.lin, f.lin), cross(a.ang, f.lin)};
}
// The power pairing of a motion and a force vector.
template <class A, class B>
inline auto dot(const Spatial<A>& s, const Spatial<B>& f) {
  return dot(s.ang, f.ang) + dot(s.lin, f.lin);
}

// A rigid body's spatial inertia about the frame's reference point, world axes: mass m (kg),
// first moment h = m c (kg m, c the centre of mass relative to the reference point) and the
// rotational inertia about the reference point Ī = I_c + m (|c|² 1 − c cᵀ) (kg m², symmetric).
struct SpatialInertia {
  double m = 0;
  Vec3<double> h{};
  double xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;

  SpatialInertia& operator+=(const SpatialInertia& o) {
    m += o.m;
    h += o.h;
    xx += o.xx, yy += o.yy, zz += o.zz, xy += o.xy, xz += o.xz, yz += o.yz;
    return *this;
  }
  // Ī w.
  template <class T>
  auto rotational(const Vec3<T>& w) const {
    using R = decltype(xx * w.x + xy * w.y);
    return Vec3<R>{xx * w.x + xy * w.y + xz * w.z, xy * w.x + yy * w.y + yz * w.z,
                   xz * w.x + yz * w.y + zz * w.z};
  }
  // The momentum (or, of an acceleration, the force) I v.
  template <class T>
  auto operator*(const Spatial<T>& v) const {
    auto ang = rotational(v.ang) + cross(h, v.lin);
    auto lin = scaled(m, v.lin) - cross(h, v.ang);
    return Spatial<decltype(ang.x)>{ang, lin};
  }
};

// The skeleton's structure as the recursion walks it. Joints are in skeleton order (parents
// before children, skeleton.hpp).
struct DynamicsTopology {
  struct JointInfo {
    int parent = -1;
    int begin = 0, end = 0;  // this joint's channels: order[begin, end)
  };
  std::vector<JointInfo> joints;
  // Every channel (frame index), each joint's in kinematic order: position channels first (the
  // translation comes before the rotation whatever order the file lists them in), then rotation
  // channels as listed.
  std::vector<int> order;
  int channel_count = 0;

  // Fills `out` for `skeleton`, reusing its storage (no allocation when sizes have not grown).
  static void build(const motion::Skeleton& skeleton, DynamicsTopology& out);
  static DynamicsTopology of(const motion::Skeleton& skeleton) {
    DynamicsTopology t;
    build(skeleton, t);
    return t;
  }
};

// Configuration-dependent quantities of one frame, all in double.
struct FrameKinematics {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // world, metres: joint 0's origin, the reference point
  // Per channel (frame index): its motion per unit rate, about `origin`, world axes. A rotation
  // channel: (ω, (p − origin) × ω) with ω its unit world axis and p its joint's origin; a position
  // channel: (0, d) with d the parent frame's unit axis it slides along.
  std::vector<Spatial<double>> axis;
  std::vector<SpatialInertia> inertia;   // per joint: its segment about `origin`, world axes
  std::vector<Eigen::Isometry3d> world;  // per joint: world from joint frame (forward kinematics)

  void resize(int joints, int channels) {
    axis.resize(static_cast<std::size_t>(channels));
    inertia.resize(static_cast<std::size_t>(joints));
    world.resize(static_cast<std::size_t>(joints));
  }
};

// Forward kinematics of one frame's values q (skeleton.channel_count(), metres and radians) into
// `out` (resized when needed), for a checked `body` (check_body_model in dynamics.hpp). The
// transforms equal motion::forward_kinematics'.
void compute_frame_kinematics(const BodyModel& body, motion::FrameRef q, FrameKinematics& out);

// Per-joint storage of the recursion for scalar types V (velocities), A (accelerations) and F
// (forces).
template <class V, class A, class F>
struct RneaBuffers {
  std::vector<Spatial<V>> v;
  std::vector<Spatial<A>> a;
  std::vector<Spatial<F>> f;
  void resize(int joints) {
    v.resize(static_cast<std::size_t>(joints));
    a.resize(static_cast<std::size_t>(joints));
    f.resize(static_cast<std::size_t>(joints));
  }
};

// One inverse dynamics pass: the generalised force of every channel that moves the figure with
// channel rates qd(c) (convertible to V) and accelerations qdd(c) (convertible to A) under
// gravity `gravity` (world, m/s², components convertible to A), handed to tau(c, F) once per
// channel (N for position channels, N m for rotation ones). The segment of joint `scaled_joint`
// (−1: none) has its mass and inertia multiplied by `scale` (a double, or a polynomial variable
// whose product with an A converts to F). `external`: empty, or per joint the spatial force the
// environment applies to that segment (about kin.origin, world axes; only when F is double).
// The root channels' forces are the residual the environment must supply: position channels the
// world force along their axis, rotation channels the moment about the root joint's origin.
// `buf` is resized to the joint count when needed.
template <class V, class A, class F, class Qd, class Qdd, class G, class K, class Tau>
void rnea_pass(const DynamicsTopology& topo, const FrameKinematics& kin, Qd&& qd, Qdd&& qdd,
               const Vec3<G>& gravity, int scaled_joint, const K& scale,
               std::span<const Spatial<double>> external, RneaBuffers<V, A, F>& buf, Tau&& tau) {
  const int joints = static_cast<int>(topo.joints.size());
  if constexpr (!std::is_same_v<F, double>) {
    if (!external.empty()) throw std::invalid_argument("rnea_pass: external forces need double forces");
  }
  if (buf.v.size() != static_cast<std::size_t>(joints)) buf.resize(joints);
  Spatial<A> a0;
  a0.lin -= gravity;
  for (int j = 0; j < joints; ++j) {
    const DynamicsTopology::JointInfo& jt = topo.joints[static_cast<std::size_t>(j)];
    Spatial<V> v = jt.parent < 0 ? Spatial<V>{} : buf.v[static_cast<std::size_t>(jt.parent)];
    Spatial<A> a = jt.parent < 0 ? a0 : buf.a[static_cast<std::size_t>(jt.parent)];
    for (int k = jt.begin; k < jt.end; ++k) {
      const int c = topo.order[static_cast<std::size_t>(k)];
      const Spatial<double>& s = kin.axis[static_cast<std::size_t>(c)];
      const Spatial<V> sq = scaled(V(qd(c)), s);
      v += sq;
      // Ṡ q̇ = v_before × S q̇ = v_after × S q̇, since S q̇ × S q̇ = 0.
      a += scaled(qdd(c), s);
      a += cross_motion(v, sq);
    }
    buf.v[static_cast<std::size_t>(j)] = v;
    buf.a[static_cast<std::size_t>(j)] = a;
    const SpatialInertia& I = kin.inertia[static_cast<std::size_t>(j)];
    Spatial<F>& f = buf.f[static_cast<std::size_t>(j)];
    if (I.m == 0 && I.xx == 0 && I.yy == 0 && I.zz == 0) {
      f = Spatial<F>{};
    } else {
      auto fj = I * a;
      fj += cross_force(v, I * v);
      if (j == scaled_joint)
        f = scaled(scale, fj);
      else
        f = fj;
    }
    if constexpr (std::is_same_v<F, double>) {
      if (!external.empty()) f -= external[static_cast<std::size_t>(j)];
    }
  }
  for (int j = joints - 1; j >= 0; --j) {
    const DynamicsTopology::JointInfo& jt = topo.joints[static_cast<std::size_t>(j)];
    const Spatial<F>& f = buf.f[static_cast<std::size_t>(j)];
    for (int k = jt.begin; k < jt.end; ++k) {
      const int c = topo.order[static_cast<std::size_t>(k)];
      tau(c, dot(kin.axis[static_cast<std::size_t>(c)], f));
    }
    if (jt.parent >= 0) buf.f[static_cast<std::size_t>(jt.parent)] += f;
  }
}

}  // namespace kg::body
