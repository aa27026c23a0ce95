// Inverse dynamics (dynamics.hpp, rnea.hpp):
//   - τ equals KDL's ChainIdSolver_RNE on fixed-base chains (random lengths, channel orders, ASF
//     axes, position channels, masses, inertias, external forces), and KDL's TreeIdSolver_RNE on
//     floating-base trees (root channels as joints from KDL's base) and a CMU skeleton;
//   - on floating-base trees (several roots, position channels on any joint, a rotated
//     file_to_world) and on CMU and Bandai clips: τ = M q̈ + C + G with M from the composite rigid
//     body algorithm, M against the kinetic energy of forward kinematics, C against the Lagrangian
//     (derivatives of M), G and external forces against point Jacobians (kinematics.hpp,
//     independent code);
//   - the root's residual is the force and the moment about the root joint that hold the figure;
//   - the path polynomials (frame_torques, the mass-scale variant, path_torques) reproduce the double
//   recursion
//     at random ṗ, p̈, gravity and mass scale, on real clip frames;
//   - a ballistic projectile needs no root residual, at any playback speed with gravity scaled by ṗ²;
//   - bad input is refused with a message.
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>

#include <Eigen/QR>

#ifdef KG_HAVE_KDL
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>

#include "../support/kdl_body.hpp"
#endif

#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/path.hpp"

using namespace kg;
using body::BodyModel;
using Catch::Matchers::Contains;
using motion::ChannelKind;

namespace {

const std::string kData = KG_DATA_DIR;

double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

Eigen::Vector3d random_vector(std::mt19937& rng, double half) {
  return {uniform(rng, -half, half), uniform(rng, -half, half), uniform(rng, -half, half)};
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

struct Shape {
  int joints = 5;
  bool chain = true;          // each joint the child of the previous one; else a random tree
  bool fixed_root = true;     // roots have no channels; else 3 position + 3 rotation channels
  int roots = 1;              // joints 0..roots-1 are roots
  bool positions = false;     // position channels on other joints too (half of them)
  bool axes = true;           // ASF axes on half the joints
  bool rotate_world = false;  // a random file_to_world
};

// Rotation channels on no two neighbouring equal axes, with position channels (when given) slipped
// in at random places of the list: the kinematic order must not depend on the listed one.
std::vector<motion::Channel> random_channels(std::mt19937& rng, int rotations,
                                             std::vector<int> position_axes) {
  std::vector<motion::Channel> ch;
  int last = -1;
  for (int i = 0; i < rotations; ++i) {
    int a;
    do a = std::uniform_int_distribution<int>(0, 2)(rng);
    while (a == last);
    last = a;
    ch.push_back({static_cast<ChannelKind>(3 + a)});
  }
  std::shuffle(position_axes.begin(), position_axes.end(), rng);
  for (int a : position_axes) {
    const auto at = std::uniform_int_distribution<std::size_t>(0, ch.size())(rng);
    ch.insert(ch.begin() + static_cast<std::ptrdiff_t>(at), motion::Channel{static_cast<ChannelKind>(a)});
  }
  return ch;
}

std::shared_ptr<motion::Skeleton> random_skeleton(std::mt19937& rng, const Shape& shape) {
  auto s = std::make_shared<motion::Skeleton>();
  if (shape.rotate_world) s->file_to_world = random_rotation(rng);
  for (int j = 0; j < shape.joints; ++j) {
    motion::Joint jt;
    jt.name = std::to_string(j);
    jt.name.insert(0, 1, 'j');
    const bool root = j < shape.roots;
    jt.parent = root ? -1 : shape.chain ? j - 1 : std::uniform_int_distribution<int>(0, j - 1)(rng);
    jt.offset = random_vector(rng, 0.4);
    if (root) {
      if (!shape.fixed_root) jt.channels = random_channels(rng, 3, {0, 1, 2});
    } else {
      std::vector<int> positions;
      if (shape.positions && rng() % 2 == 0)
        for (int a = 0; a < 3; ++a)
          if (rng() % 3 != 0) positions.push_back(a);
      jt.channels = random_channels(rng, std::uniform_int_distribution<int>(0, 3)(rng), positions);
    }
    if (shape.axes && rng() % 2 == 0) jt.axis = random_rotation(rng);
    s->add_joint(jt);
  }
  return s;
}

// What a whole BodyModel carries besides the inertias (check_body_model asks for it): a class
// per joint, unlimited torques. The dynamics read neither.
void complete(BodyModel& b) {
  b.segment_class.assign(b.segments.size(), "");
  for (std::size_t j = 0; j < b.segments.size(); ++j)
    if (b.segments[j].mass > 0) b.segment_class[j] = "random";
  const int channels = b.skeleton->channel_count();
  b.torque_min = Eigen::VectorXd::Constant(channels, -std::numeric_limits<double>::infinity());
  b.torque_max = Eigen::VectorXd::Constant(channels, std::numeric_limits<double>::infinity());
}

// Random masses (a fifth of the segments massless), centres of mass and inertias.
BodyModel random_body(std::shared_ptr<const motion::Skeleton> s, std::mt19937& rng) {
  BodyModel b;
  b.skeleton = s;
  b.segments.resize(static_cast<std::size_t>(s->joint_count()));
  for (body::SegmentInertia& seg : b.segments) {
    if (rng() % 5 == 0) continue;
    seg.mass = uniform(rng, 0.5, 8);
    seg.com = random_vector(rng, 0.3);
    // A rigid body's: principal moments from second moments x, y, z of its mass (each moment at
    // most the sum of the other two), in random axes.
    Eigen::Matrix3d A;
    for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = uniform(rng, -1, 1);
    const Eigen::Matrix3d R = Eigen::HouseholderQR<Eigen::Matrix3d>(A).householderQ();
    const double x = uniform(rng, 0.005, 0.2), y = uniform(rng, 0.005, 0.2), z = uniform(rng, 0.005, 0.2);
    seg.inertia = R * Eigen::Vector3d(y + z, x + z, x + y).asDiagonal() * R.transpose();
  }
  complete(b);
  return b;
}

// Channel values: positions within a metre, angles anywhere.
Eigen::VectorXd random_values(const motion::Skeleton& s, std::mt19937& rng, double pos, double rot) {
  Eigen::VectorXd q(s.channel_count());
  for (int c = 0; c < s.channel_count(); ++c) {
    auto [j, i] = s.channel_owner(c);
    q[c] = motion::is_rotation(s.joint(j).channels[static_cast<std::size_t>(i)].kind)
               ? uniform(rng, -rot, rot)
               : uniform(rng, -pos, pos);
  }
  return q;
}

double inf_norm(const Eigen::VectorXd& v) {
  return v.size() ? v.cwiseAbs().maxCoeff() : 0.0;  // a chain may draw no channel at all
}

// |a - b| <= tol * max(1, |b|_inf) entrywise.
void check_close(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double tol) {
  REQUIRE(a.size() == b.size());
  const double scale = std::max(1.0, inf_norm(b));
  INFO("scale " << scale << "\n  got      " << a.transpose() << "\n  expected " << b.transpose());
  CHECK(inf_norm(a - b) <= tol * scale);
}

std::vector<body::ExternalForce> random_forces(const motion::Skeleton& s, std::mt19937& rng, int n) {
  std::vector<body::ExternalForce> f;
  for (int i = 0; i < n; ++i)
    f.push_back({.joint = std::uniform_int_distribution<int>(0, s.joint_count() - 1)(rng),
                 .point = random_vector(rng, 1.0),
                 .force = random_vector(rng, 50),
                 .torque = rng() % 2 ? random_vector(rng, 10) : Eigen::Vector3d::Zero()});
  return f;
}

// A floating-base figure thrown through the air: a root (XYZ position, ZYX rotation) spinning at a
// constant rate about its Y axis (a principal axis of the whole), tilted by a constant Z rotation,
// with two arms at +-0.5 m along its X axis (each with a rotation channel held still, inertia
// symmetric about X), its centre of mass on the root's origin following a parabola.
motion::Motion projectile(BodyModel& body, const Eigen::Vector3d& g, double fps, int frames) {
  auto s = std::make_shared<motion::Skeleton>();
  s->add_joint({.name = "body",
                .channels = {{ChannelKind::Xposition},
                             {ChannelKind::Yposition},
                             {ChannelKind::Zposition},
                             {ChannelKind::Zrotation},
                             {ChannelKind::Yrotation},
                             {ChannelKind::Xrotation}}});
  s->add_joint({.name = "left", .parent = 0, .offset = {0.5, 0, 0}, .channels = {{ChannelKind::Xrotation}}});
  s->add_joint(
      {.name = "right", .parent = 0, .offset = {-0.5, 0, 0}, .channels = {{ChannelKind::Xrotation}}});
  body.skeleton = s;
  body.segments = {
      {.mass = 30, .com = Eigen::Vector3d::Zero(), .inertia = Eigen::Vector3d(2.0, 1.5, 1.0).asDiagonal()},
      {.mass = 4, .com = Eigen::Vector3d::Zero(), .inertia = Eigen::Vector3d(0.1, 0.3, 0.3).asDiagonal()},
      {.mass = 4, .com = Eigen::Vector3d::Zero(), .inertia = Eigen::Vector3d(0.1, 0.3, 0.3).asDiagonal()}};
  complete(body);
  motion::Motion m{s, motion::FrameMatrix::Zero(frames, s->channel_count()), fps, "projectile"};
  const Eigen::Vector3d p0(0.3, 1.2, -0.4), v0(1.5, 4.0, 0.7);
  for (int f = 0; f < frames; ++f) {
    const double t = f / fps;
    m.values.block<1, 3>(f, 0) = (p0 + v0 * t + 0.5 * g * t * t).transpose();
    m.values(f, 3) = 0.3;                          // tilt of the spin axis
    m.values(f, 4) = motion::wrap_angle(5.0 * t);  // spin, through +-180 degrees
    m.values(f, 6) = 0.4;                          // arms turned, held
    m.values(f, 7) = -0.7;
  }
  return m;
}

std::optional<motion::Motion> load_cmu_walk() {
  const std::string asf = kData + "/cmu/asf_amc/16.asf", amc = kData + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) return std::nullopt;
  return io::import_motion(amc, asf, {}).motion;
}

std::optional<motion::Motion> load_bandai_run() {
  const std::string bvh = kData + "/other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh";
  if (!std::filesystem::exists(bvh)) return std::nullopt;
  return io::import_motion(bvh, "", {}).motion;
}

// τ = M q̈ + C + G at random velocities and accelerations at q.
void check_parts(const BodyModel& body, const Eigen::VectorXd& q, std::mt19937& rng,
                 const Eigen::Vector3d& g) {
  const motion::Skeleton& s = *body.skeleton;
  const int n = s.channel_count();
  retime::DynamicsWorkspace ws;
  const Eigen::VectorXd qd = random_values(s, rng, 2, 3), qdd = random_values(s, rng, 5, 10);
  Eigen::VectorXd tau(n), bias(n);
  Eigen::MatrixXd M(n, n);
  body::inverse_dynamics(body, q, qd, qdd, g, {}, ws, tau);
  body::mass_matrix(body, q, ws, M);
  body::bias_forces(body, q, qd, g, ws, bias);
  CHECK((M - M.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, M.cwiseAbs().maxCoeff()));
  check_close(M * qdd + bias, tau, 1e-9);
  // The mass matrix is positive definite when every channel moves some mass; at least semidefinite.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  CHECK(eig.eigenvalues().minCoeff() >= -1e-9 * eig.eigenvalues().maxCoeff());
}

// ω of every joint by central differences of forward kinematics along q̇.
std::vector<Eigen::Vector3d> angular_velocities(const motion::Skeleton& s, const Eigen::VectorXd& q,
                                                const Eigen::VectorXd& qd) {
  const double h = 1e-6;
  std::vector<Eigen::Isometry3d> w0(static_cast<std::size_t>(s.joint_count())), wp = w0, wm = w0;
  const Eigen::VectorXd qp = q + h * qd, qm = q - h * qd;
  motion::forward_kinematics(s, q.transpose(), w0);
  motion::forward_kinematics(s, qp.transpose(), wp);
  motion::forward_kinematics(s, qm.transpose(), wm);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t j = 0; j < w0.size(); ++j) {
    const Eigen::Matrix3d W = (wp[j].linear() - wm[j].linear()) / (2 * h) * w0[j].linear().transpose();
    out.emplace_back(0.5 * (W(2, 1) - W(1, 2)), 0.5 * (W(0, 2) - W(2, 0)), 0.5 * (W(1, 0) - W(0, 1)));
  }
  return out;
}

// M against kinetic energy, G and external forces against point Jacobians.
void check_against_kinematics(const BodyModel& body, const Eigen::VectorXd& q, std::mt19937& rng) {
  const motion::Skeleton& s = *body.skeleton;
  const int n = s.channel_count();
  retime::DynamicsWorkspace ws;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  motion::forward_kinematics(s, q.transpose(), world);
  Eigen::MatrixXd M(n, n);
  body::mass_matrix(body, q, ws, M);
  for (std::size_t j = 0; j < world.size(); ++j)
    CHECK(ws.kinematics.world[j].matrix().isApprox(world[j].matrix(), 1e-12));

  const Eigen::VectorXd qd = random_values(s, rng, 2, 3);
  const std::vector<Eigen::Vector3d> omega = angular_velocities(s, q, qd);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, n);
  double energy = 0;  // twice the kinetic energy
  Eigen::VectorXd gravity_torque = Eigen::VectorXd::Zero(n);
  const Eigen::Vector3d g(0.4, -9.81, 1.3);
  for (int j = 0; j < s.joint_count(); ++j) {
    const body::SegmentInertia& seg = body.segments[static_cast<std::size_t>(j)];
    motion::point_jacobian(s, q.transpose(), world, j, seg.com, J);
    const Eigen::Matrix3d R = world[static_cast<std::size_t>(j)].linear();
    const Eigen::Vector3d w = omega[static_cast<std::size_t>(j)];
    energy += seg.mass * (J * qd).squaredNorm() + w.dot(R * seg.inertia * R.transpose() * w);
    gravity_torque -= seg.mass * J.transpose() * g;
  }
  CHECK(qd.dot(M * qd) == Approx(energy).epsilon(1e-7));

  Eigen::VectorXd zero = Eigen::VectorXd::Zero(n), tau(n);
  body::inverse_dynamics(body, q, zero, zero, g, {}, ws, tau);
  check_close(tau, gravity_torque, 1e-9);

  // Coriolis and centrifugal forces from the Lagrangian: C q̇ = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q, with M's
  // derivatives by central differences of the composite rigid body algorithm.
  {
    const double h = 1e-5;
    Eigen::MatrixXd Mp(n, n), Mm(n, n);
    body::mass_matrix(body, q + h * qd, ws, Mp);
    body::mass_matrix(body, q - h * qd, ws, Mm);
    Eigen::VectorXd lagrange = (Mp - Mm) / (2 * h) * qd;
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
      e[i] = h;
      body::mass_matrix(body, q + e, ws, Mp);
      body::mass_matrix(body, q - e, ws, Mm);
      lagrange[i] -= 0.5 * qd.dot((Mp - Mm) / (2 * h) * qd);
    }
    Eigen::VectorXd coriolis(n);
    body::bias_forces(body, q, qd, Eigen::Vector3d::Zero(), ws, coriolis);
    check_close(coriolis, lagrange, 1e-6);
  }

  // A force on a segment: −Jᵀ f at its point (no couple: point_jacobian has no angular part).
  const std::vector<body::ExternalForce> pushes = {
      {.joint = s.joint_count() - 1, .point = random_vector(rng, 1), .force = random_vector(rng, 40)},
      {.joint = s.joint_count() / 2, .point = random_vector(rng, 1), .force = random_vector(rng, 40)}};
  Eigen::VectorXd expected = gravity_torque;
  for (const body::ExternalForce& p : pushes) {
    const Eigen::Vector3d local = world[static_cast<std::size_t>(p.joint)].inverse() * p.point;
    motion::point_jacobian(s, q.transpose(), world, p.joint, local, J);
    expected -= J.transpose() * p.force;
  }
  body::inverse_dynamics(body, q, zero, zero, g, pushes, ws, tau);
  check_close(tau, expected, 1e-9);
}

// frame_torques and the mass-scale variant against the double recursion at random retiming states.
void check_path_polynomials(const BodyModel& body, const motion::Motion& clip, const std::vector<int>& frames,
                            std::mt19937& rng) {
  const motion::Skeleton& s = *body.skeleton;
  const retime::PathDerivatives d = retime::path_derivatives(clip);
  retime::DynamicsWorkspace ws;
  const int n = s.channel_count();
  Eigen::VectorXd tau(n);
  const int joint = std::uniform_int_distribution<int>(0, s.joint_count() - 1)(rng);
  const retime::PathTorques all = retime::path_torques(body, clip, d);
  const retime::PathTorques heavier = retime::path_torques(body, clip, d, joint);
  REQUIRE(all.frame_count() == clip.frame_count());
  REQUIRE(heavier.frame_count() == clip.frame_count());
  CHECK(all.segment.empty());
  CHECK(all.segment_change.empty());
  CHECK(heavier.segment == s.joint(joint).name);
  CHECK(all.fps == clip.fps);
  for (int f : frames) {
    const retime::FrameTorques ft = retime::frame_torques(body, clip, d, f, ws);
    CHECK(ft.velocity == all.frames[static_cast<std::size_t>(f)].velocity);
    CHECK(ft.acceleration == all.frames[static_cast<std::size_t>(f)].acceleration);
    CHECK(ft.gravity == all.frames[static_cast<std::size_t>(f)].gravity);
    const Eigen::VectorXd q = clip.values.row(f), q1 = d.first.row(f), q2 = d.second.row(f);
    const retime::MassScaleTorques ms = retime::frame_torques_mass_scale(body, clip, d, f, joint, ws);
    CHECK(ms.change.velocity == heavier.segment_change[static_cast<std::size_t>(f)].velocity);
    CHECK(ms.base.gravity == heavier.frames[static_cast<std::size_t>(f)].gravity);
    CHECK(inf_norm(ms.base.velocity - ft.velocity) <= 1e-12 * std::max(1.0, inf_norm(ft.velocity)));
    CHECK(inf_norm(ms.base.acceleration - ft.acceleration) <=
          1e-12 * std::max(1.0, inf_norm(ft.acceleration)));
    CHECK((ms.base.gravity - ft.gravity).cwiseAbs().maxCoeff() <=
          1e-12 * std::max(1.0, ft.gravity.cwiseAbs().maxCoeff()));
    // The scaled segment moves only the channels of its joint and its ancestors.
    std::vector<bool> carries(static_cast<std::size_t>(n), false);
    for (int c : motion::influencing_channels(s, joint)) carries[static_cast<std::size_t>(c)] = true;
    for (int c = 0; c < n; ++c)
      if (!carries[static_cast<std::size_t>(c)]) {
        CHECK(ms.change.velocity[c] == 0);
        CHECK(ms.change.gravity.row(c).isZero(0));
      }
    for (int trial = 0; trial < 3; ++trial) {
      const double pdot = uniform(rng, 0.2, 3), pddot = uniform(rng, -4, 4), k = uniform(rng, 0, 12);
      const Eigen::Vector3d g = random_vector(rng, 12);
      body::inverse_dynamics(body, q, q1 * pdot, q2 * pdot * pdot + q1 * pddot, g, {}, ws, tau);
      check_close(ft.at(pdot * pdot, pddot, g), tau, 1e-9);
      BodyModel heavy = body;
      heavy.segments[static_cast<std::size_t>(joint)].mass *= k;
      heavy.segments[static_cast<std::size_t>(joint)].inertia *= k;
      body::inverse_dynamics(heavy, q, q1 * pdot, q2 * pdot * pdot + q1 * pddot, g, {}, ws, tau);
      check_close(ms.at(k).at(pdot * pdot, pddot, g), tau, 1e-9);
      check_close(heavier.edited(f, k).at(pdot * pdot, pddot, g), tau, 1e-9);
    }
  }
}

}  // namespace

#ifdef KG_HAVE_KDL
namespace {

struct KdlInput {
  KDL::JntArray q, qd, qdd;
};

// Our channel values in KDL's joint order (DynamicsTopology's).
KdlInput kdl_input(const motion::Skeleton& s, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                   const Eigen::VectorXd& qdd) {
  const std::vector<int> order = body::DynamicsTopology::of(s).order;
  const auto n = static_cast<unsigned>(order.size());
  KdlInput in{KDL::JntArray(n), KDL::JntArray(n), KDL::JntArray(n)};
  for (unsigned i = 0; i < n; ++i) {
    in.q(i) = q[order[i]];
    in.qd(i) = qd[order[i]];
    in.qdd(i) = qdd[order[i]];
  }
  return in;
}

Eigen::VectorXd from_kdl(const motion::Skeleton& s, const KDL::JntArray& tau) {
  const std::vector<int> order = body::DynamicsTopology::of(s).order;
  Eigen::VectorXd out(s.channel_count());
  for (std::size_t i = 0; i < order.size(); ++i) out[order[i]] = tau(static_cast<unsigned>(i));
  return out;
}

// KDL wants each external wrench in its segment's frame about that frame's origin.
KDL::Wrench kdl_wrench(const body::ExternalForce& p, const Eigen::Isometry3d& W) {
  const Eigen::Vector3d moment = (p.point - W.translation()).cross(p.force) + p.torque;
  return KDL::Wrench(test::kdl(Eigen::Vector3d(W.linear().transpose() * p.force)),
                     test::kdl(Eigen::Vector3d(W.linear().transpose() * moment)));
}

// Ours against KDL's tree solver at random velocities, accelerations, gravity and pushes.
void check_tree_against_kdl(const BodyModel& body, const Eigen::VectorXd& q, std::mt19937& rng) {
  const motion::Skeleton& s = *body.skeleton;
  const test::KdlBody k = test::kdl_body(body);
  REQUIRE(static_cast<int>(k.tree.getNrOfJoints()) == s.channel_count());
  const Eigen::VectorXd qd = random_values(s, rng, 2, 3), qdd = random_values(s, rng, 5, 10);
  const Eigen::Vector3d g = random_vector(rng, 10);
  const std::vector<body::ExternalForce> pushes = random_forces(s, rng, 3);
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  motion::forward_kinematics(s, q.transpose(), world);
  KDL::WrenchMap wrenches;
  for (const body::ExternalForce& p : pushes) {
    KDL::Wrench& w = wrenches[k.last_segment[static_cast<std::size_t>(p.joint)]];
    w = w + kdl_wrench(p, world[static_cast<std::size_t>(p.joint)]);
  }
  const KdlInput in = kdl_input(s, q, qd, qdd);
  KDL::JntArray ktau(in.q.rows());
  KDL::TreeIdSolver_RNE solver(k.tree, test::kdl(g));
  REQUIRE(solver.CartToJnt(in.q, in.qd, in.qdd, wrenches, ktau) == 0);
  check_close(body::inverse_dynamics(body, q, qd, qdd, g, pushes), from_kdl(s, ktau), 1e-9);
}

}  // namespace

TEST_CASE("inverse dynamics equals KDL's ChainIdSolver_RNE on fixed-base chains") {
  std::mt19937 rng(11);
  for (int links : {1, 2, 3, 5, 12, 30}) {
    for (int trial = 0; trial < 6; ++trial) {
      const bool positions = trial % 2 == 1;
      INFO(links << " links, trial " << trial);
      auto s = random_skeleton(rng, {.joints = links + 1, .positions = positions});
      const BodyModel body = random_body(s, rng);
      const test::KdlBody k = test::kdl_body(body);
      const int n = s->channel_count();
      REQUIRE(static_cast<int>(k.chain.getNrOfJoints()) == n);

      const Eigen::VectorXd q = random_values(*s, rng, 0.5, std::numbers::pi);
      const Eigen::VectorXd qd = random_values(*s, rng, 2, 3), qdd = random_values(*s, rng, 5, 10);
      const Eigen::Vector3d g = random_vector(rng, 10);
      const std::vector<body::ExternalForce> pushes = random_forces(*s, rng, trial % 3);
      std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s->joint_count()));
      motion::forward_kinematics(*s, q.transpose(), world);
      KDL::Wrenches wrenches(k.chain.getNrOfSegments(), KDL::Wrench::Zero());
      for (const body::ExternalForce& p : pushes) {
        KDL::Wrench& w =
            wrenches[static_cast<std::size_t>(k.last_chain_segment[static_cast<std::size_t>(p.joint)])];
        w = w + kdl_wrench(p, world[static_cast<std::size_t>(p.joint)]);
      }
      const KdlInput in = kdl_input(*s, q, qd, qdd);
      KDL::JntArray ktau(in.q.rows());
      KDL::ChainIdSolver_RNE solver(k.chain, test::kdl(g));
      REQUIRE(solver.CartToJnt(in.q, in.qd, in.qdd, wrenches, ktau) == 0);
      const Eigen::VectorXd expected = from_kdl(*s, ktau);

      retime::DynamicsWorkspace ws;
      Eigen::VectorXd tau(n);
      body::inverse_dynamics(body, q, qd, qdd, g, pushes, ws, tau);
      check_close(tau, expected, 1e-9);
      // The allocating overload agrees.
      check_close(body::inverse_dynamics(body, q, qd, qdd, g, pushes), expected, 1e-9);
    }
  }
}

TEST_CASE("inverse dynamics equals KDL's TreeIdSolver_RNE on floating-base trees and a CMU skeleton") {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 8; ++trial) {
    INFO("trial " << trial);
    auto s = random_skeleton(rng, {.joints = 10,
                                   .chain = false,
                                   .fixed_root = false,
                                   .roots = 1 + trial % 3,
                                   .positions = true,
                                   .rotate_world = trial % 2 == 1});
    const BodyModel body = random_body(s, rng);
    check_tree_against_kdl(body, random_values(*s, rng, 2, std::numbers::pi), rng);
  }
  if (auto clip = load_cmu_walk()) {
    const BodyModel body = random_body(clip->skeleton, rng);
    check_tree_against_kdl(body, clip->values.row(clip->frame_count() / 2).transpose(), rng);
  } else {
    WARN("skipped: 16.asf / 16_15.amc not found in " << kData << "/cmu/asf_amc");
  }
}
#else
TEST_CASE("inverse dynamics equals KDL's recursive Newton-Euler solvers") {
  WARN("skipped: built without KDL (Debian liborocos-kdl-dev, pkg-config orocos-kdl)");
}
#endif

TEST_CASE("on floating-base trees, τ = M q̈ + C + G, and M, C, G, external forces match kinematics") {
  std::mt19937 rng(5);
  const std::vector<Shape> shapes = {
      {.joints = 6, .chain = false, .fixed_root = false},
      {.joints = 12, .chain = false, .fixed_root = false, .positions = true, .rotate_world = true},
      {.joints = 9, .chain = false, .fixed_root = false, .roots = 3, .positions = true, .rotate_world = true},
      {.joints = 8, .chain = true, .fixed_root = true, .roots = 2, .positions = true},
  };
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    for (int trial = 0; trial < 4; ++trial) {
      INFO("shape " << i << ", trial " << trial);
      auto s = random_skeleton(rng, shapes[i]);
      const BodyModel body = random_body(s, rng);
      const Eigen::VectorXd q = random_values(*s, rng, 3, std::numbers::pi);
      check_parts(body, q, rng, random_vector(rng, 10));
      check_against_kinematics(body, q, rng);
    }
  }
}

TEST_CASE(
    "τ = M q̈ + C + G on a CMU skeleton (ASF axes) and a Bandai one (position channels on every joint)") {
  std::mt19937 rng(8);
  int ran = 0;
  if (auto clip = load_cmu_walk()) {
    const BodyModel body = random_body(clip->skeleton, rng);
    for (int f : {0, clip->frame_count() / 2, clip->frame_count() - 1}) {
      const Eigen::VectorXd q = clip->values.row(f);
      check_parts(body, q, rng, {0, -9.81, 0});
      check_against_kinematics(body, q, rng);
    }
    ++ran;
  } else {
    WARN("skipped: 16.asf / 16_15.amc not found in " << kData << "/cmu/asf_amc");
  }
  if (auto clip = load_bandai_run()) {
    const BodyModel body = random_body(clip->skeleton, rng);
    const Eigen::VectorXd q = clip->values.row(clip->frame_count() / 3);
    check_parts(body, q, rng, {0, -9.81, 0});
    check_against_kinematics(body, q, rng);
    ++ran;
  } else {
    WARN("skipped: the Bandai run BVH not found in " << kData << "/other_skeletons/bandai_namco");
  }
  if (ran == 0) WARN("skipped: no clip data");
}

TEST_CASE("the root's residual holds the figure: its weight and the moment about the root joint") {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 5; ++trial) {
    auto s = random_skeleton(rng, {.joints = 10, .chain = false, .fixed_root = false, .positions = true});
    const BodyModel body = random_body(s, rng);
    const Eigen::VectorXd q = random_values(*s, rng, 2, std::numbers::pi);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s->channel_count());
    const Eigen::Vector3d g(0.5, -9.81, -0.2);
    const Eigen::VectorXd tau = body::inverse_dynamics(body, q, zero, zero, g);

    std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s->joint_count()));
    motion::forward_kinematics(*s, q.transpose(), world);
    const double mass = body.total_mass();
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    for (int j = 0; j < s->joint_count(); ++j)
      com += body.segments[static_cast<std::size_t>(j)].mass *
             (world[static_cast<std::size_t>(j)] * body.segments[static_cast<std::size_t>(j)].com);
    com /= mass;
    const Eigen::Vector3d support = -mass * g;  // what the environment must push with
    const motion::Joint& root = s->joint(0);
    const Eigen::Vector3d p = world[0].translation();
    // Rotation channel m turns about world axis R_before_m e_axis through the root's origin.
    Eigen::Matrix3d M = root.axis;
    for (std::size_t i = 0; i < root.channels.size(); ++i) {
      const motion::ChannelKind kind = root.channels[i].kind;
      const int a = motion::axis_index(kind);
      const double expected = motion::is_rotation(kind) ? M.col(a).dot((com - p).cross(support)) : support[a];
      CHECK(tau[root.first_channel + static_cast<int>(i)] == Approx(expected).margin(1e-9 * mass * 10));
      if (motion::is_rotation(kind))
        M = M * Eigen::AngleAxisd(q[root.first_channel + static_cast<int>(i)], Eigen::Vector3d::Unit(a));
    }
  }
}

TEST_CASE("path polynomials reproduce the double recursion at random ṗ, p̈, gravity and mass scale") {
  std::mt19937 rng(13);
  {
    auto s = random_skeleton(rng, {.joints = 9,
                                   .chain = false,
                                   .fixed_root = false,
                                   .roots = 2,
                                   .positions = true,
                                   .rotate_world = true});
    const BodyModel body = random_body(s, rng);
    motion::Motion clip{s, motion::FrameMatrix(40, s->channel_count()), 60, "random"};
    const Eigen::VectorXd a = random_values(*s, rng, 1, 2), b = random_values(*s, rng, 1, 2);
    for (int f = 0; f < clip.frame_count(); ++f)
      clip.values.row(f) = (a * std::sin(0.1 * f) + b * std::cos(0.23 * f)).transpose();
    check_path_polynomials(body, clip, {0, 7, 20, 39}, rng);
  }
  if (auto clip = load_cmu_walk()) {
    const BodyModel body = random_body(clip->skeleton, rng);
    check_path_polynomials(body, *clip, {1, 150, clip->frame_count() - 2}, rng);
  } else {
    WARN("skipped: 16.asf / 16_15.amc not found in " << kData << "/cmu/asf_amc");
  }
  if (auto clip = load_bandai_run()) {
    const BodyModel body = random_body(clip->skeleton, rng);
    check_path_polynomials(body, *clip, {3, clip->frame_count() / 2}, rng);
  } else {
    WARN("skipped: the Bandai run BVH not found in " << kData << "/other_skeletons/bandai_namco");
  }
}

TEST_CASE("a ballistic projectile needs no root residual, at any speed with gravity scaled by ṗ²") {
  const Eigen::Vector3d g(0, -9.81, 0);
  BodyModel body;
  const motion::Motion clip = projectile(body, g, 120, 90);
  const retime::PathDerivatives d = retime::path_derivatives(clip);
  retime::DynamicsWorkspace ws;
  const double weight = body.total_mass() * g.norm();
  for (int f : {0, 1, 45, 88, 89}) {
    const retime::FrameTorques ft = retime::frame_torques(body, clip, d, f, ws);
    INFO("frame " << f);
    CHECK(inf_norm(ft.at(1, 0, g).head(6)) <= 1e-9 * weight);
    CHECK(inf_norm(ft.at(4, 0, 4 * g).head(6)) <= 1e-9 * weight);        // twice as fast, 4 g
    CHECK(inf_norm(ft.at(0.25, 0, 0.25 * g).head(6)) <= 1e-9 * weight);  // half as fast, g / 4
    // Twice as fast under the same gravity, the environment must pull down by three weights.
    const Eigen::VectorXd fast = ft.at(4, 0, g);
    CHECK(fast[1] == Approx(-3 * weight).epsilon(1e-9));
    // Slowing down (p̈ < 0) mid-flight needs a push against the velocity.
    const Eigen::VectorXd braking = ft.at(1, -0.5, g);
    CHECK(braking.head(3).dot(d.first.row(f).head(3).transpose()) < 0);
  }
}

TEST_CASE("inverse dynamics refuses bad input with a message") {
  std::mt19937 rng(2);
  auto s = random_skeleton(rng, {.joints = 4, .fixed_root = false});
  BodyModel body = random_body(s, rng);
  const int n = s->channel_count();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(n), shorter = Eigen::VectorXd::Zero(n - 1);
  retime::DynamicsWorkspace ws;
  Eigen::VectorXd tau(n);
  const Eigen::Vector3d g(0, -9.81, 0);
  CHECK_THROWS_WITH(body::inverse_dynamics(body, shorter, q, q, g, {}, ws, tau),
                    Contains("q has " + std::to_string(n - 1) + " values"));
  CHECK_THROWS_WITH(body::inverse_dynamics(body, q, q, shorter, g, {}, ws, tau), Contains("q acceleration"));
  const std::vector<body::ExternalForce> bad_joint = {{.joint = 9}};
  CHECK_THROWS_WITH(body::inverse_dynamics(body, q, q, q, g, bad_joint, ws, tau),
                    Contains("acts on joint 9") && Contains("expected 0..3"));
  const std::vector<body::ExternalForce> nan_force = {{.joint = 1, .force = {NAN, 0, 0}}};
  CHECK_THROWS_WITH(body::inverse_dynamics(body, q, q, q, g, nan_force, ws, tau), Contains("not finite"));
  Eigen::MatrixXd small(n - 1, n);
  CHECK_THROWS_WITH(body::mass_matrix(body, q, ws, small), Contains("expected " + std::to_string(n)));

  BodyModel bad = body;
  bad.segments.pop_back();
  CHECK_THROWS_WITH(body::inverse_dynamics(bad, q, q, q, g, {}, ws, tau),
                    Contains("3 segments for 4 joints"));
  bad = body;
  bad.segments[2].mass = -1;
  CHECK_THROWS_WITH(body::inverse_dynamics(bad, q, q, q, g, {}, ws, tau), Contains("segment 'j2': mass"));
  bad = body;
  bad.segments[1].inertia(0, 1) += 1;
  CHECK_THROWS_WITH(body::bias_forces(bad, q, q, g, ws, tau), Contains("'j1': inertia is not symmetric"));
  bad = body;
  bad.skeleton = nullptr;
  CHECK_THROWS_WITH(body::inverse_dynamics(bad, q, q, q, g, {}, ws, tau), Contains("no skeleton"));

  motion::Motion clip{s, motion::FrameMatrix::Zero(5, n), 30, "still"};
  const retime::PathDerivatives d = retime::path_derivatives(clip);
  CHECK_THROWS_WITH(retime::frame_torques(body, clip, d, 5, ws), Contains("frame 5 out of range"));
  CHECK_THROWS_WITH(retime::frame_torques_mass_scale(body, clip, d, 0, 4, ws),
                    Contains("joint 4 out of range"));
  CHECK_THROWS_WITH(retime::path_torques(body, clip, d, 7), Contains("segment 7 out of range"));
  motion::Motion longer = clip;
  longer.values = motion::FrameMatrix::Zero(6, n);
  CHECK_THROWS_WITH(retime::frame_torques(body, longer, d, 0, ws),
                    Contains("expected path_derivatives(clip)"));
  auto other = random_skeleton(rng, {.joints = 6, .fixed_root = false});
  motion::Motion foreign{other, motion::FrameMatrix::Zero(5, other->channel_count()), 30, "foreign"};
  CHECK_THROWS_WITH(retime::frame_torques(body, foreign, retime::path_derivatives(foreign), 0, ws),
                    Contains("clip 'foreign' has 6 joints"));
}
