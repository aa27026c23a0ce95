#include "synth_detail.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "kg/motion/rotations.hpp"

namespace kg::synth::detail {

// ---------------------------------------------------------------------------------------------
// Curves

void Curve::add_poly(double t0, double t1, const std::array<double, 6>& c) {
  if (!(t1 > t0)) throw std::logic_error("synth curve: empty or reversed piece");
  if (!pieces_.empty() && std::abs(pieces_.back().t1 - t0) > 1e-9)
    throw std::logic_error("synth curve: pieces must be contiguous");
  pieces_.push_back({t0, t1, c});
}

void Curve::add_hermite(double t0, double t1, double y0, double m0, double y1, double m1) {
  const double h = t1 - t0;
  add_poly(t0, t1,
           {y0, m0, (3 * (y1 - y0) / h - 2 * m0 - m1) / h, (2 * (y0 - y1) / h + m0 + m1) / (h * h), 0, 0});
}

void Curve::add_quintic(double t0, double t1, double y0, double v0, double a0, double y1, double v1,
                        double a1) {
  const double T = t1 - t0, T2 = T * T, T3 = T2 * T;
  const double d = y1 - y0;
  add_poly(t0, t1,
           {y0, v0, a0 / 2, (20 * d - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T2) / (2 * T3),
            (-30 * d + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T2) / (2 * T3 * T),
            (12 * d - 6 * (v1 + v0) * T + (a1 - a0) * T2) / (2 * T3 * T2)});
}

const Curve::Piece* Curve::find(double t) const {
  if (pieces_.empty()) throw std::logic_error("synth curve: evaluated while empty");
  auto it =
      std::lower_bound(pieces_.begin(), pieces_.end(), t, [](const Piece& p, double x) { return p.t1 < x; });
  if (it == pieces_.end()) return nullptr;
  return &*it;
}

double Curve::value(double t) const {
  const Piece* p = find(t);
  if (!p) {
    p = &pieces_.back();
    t = p->t1;
  }
  const double x = std::max(0.0, t - p->t0);
  const auto& c = p->c;
  return c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * (c[4] + x * c[5]))));
}

double Curve::slope(double t) const {
  const Piece* p = find(t);
  if (!p || t < p->t0) return 0;
  const double x = t - p->t0;
  const auto& c = p->c;
  return c[1] + x * (2 * c[2] + x * (3 * c[3] + x * (4 * c[4] + x * 5 * c[5])));
}

double Curve::second(double t) const {
  const Piece* p = find(t);
  if (!p || t < p->t0) return 0;
  const double x = t - p->t0;
  const auto& c = p->c;
  return 2 * c[2] + x * (6 * c[3] + x * (12 * c[4] + x * 20 * c[5]));
}

Curve monotone_curve(const std::vector<std::pair<double, double>>& keys) {
  Curve curve;
  const std::size_t n = keys.size();
  if (n == 0) throw std::logic_error("synth curve: no keys");
  if (n == 1) {
    curve.add_hold(keys[0].first, keys[0].first + 1, keys[0].second);
    return curve;
  }
  std::vector<double> delta(n - 1), slope(n, 0.0);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double h = keys[i + 1].first - keys[i].first;
    if (!(h > 0)) throw std::logic_error("synth curve: key times must increase");
    delta[i] = (keys[i + 1].second - keys[i].second) / h;
  }
  // Fritsch-Butland weighted harmonic mean: monotone between keys, zero at extrema.
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (delta[i - 1] * delta[i] <= 0) continue;
    const double h0 = keys[i].first - keys[i - 1].first, h1 = keys[i + 1].first - keys[i].first;
    const double w0 = 2 * h1 + h0, w1 = h1 + 2 * h0;
    slope[i] = (w0 + w1) / (w0 / delta[i - 1] + w1 / delta[i]);
  }
  for (std::size_t i = 0; i + 1 < n; ++i)
    curve.add_hermite(keys[i].first, keys[i + 1].first, keys[i].second, slope[i], keys[i + 1].second,
                      slope[i + 1]);
  return curve;
}

double hermite(double y0, double m0, double y1, double m1, double h, double s) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * h * m0 + (-2 * s3 + 3 * s2) * y1 +
         (s3 - s2) * h * m1;
}

double hermite_slope(double y0, double m0, double y1, double m1, double h, double s) {
  const double s2 = s * s;
  return ((6 * s2 - 6 * s) * y0 + (3 * s2 - 4 * s + 1) * h * m0 + (-6 * s2 + 6 * s) * y1 +
          (3 * s2 - 2 * s) * h * m1) /
         h;
}

Eigen::Vector3d hermite(const Eigen::Vector3d& y0, const Eigen::Vector3d& m0, const Eigen::Vector3d& y1,
                        const Eigen::Vector3d& m1, double h, double s) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * h * m0 + (-2 * s3 + 3 * s2) * y1 +
         (s3 - s2) * h * m1;
}

// ---------------------------------------------------------------------------------------------
// Feet

FootGeometry::FootGeometry(const Figure& figure) {
  const FigureDimensions& d = figure.dims;
  heel_offset_ = figure.heel_local;
  ball_offset_ = Eigen::Vector3d(0, d.ball_height - d.ankle_height, d.ball_forward);
  toe_tip_offset_ = figure.toe_tip_local;
  ball_sole_offset_ = Eigen::Vector3d(0, -d.ball_height, 0);
}

Eigen::Vector3d FootGeometry::ankle_about(const Eigen::Vector3d& pivot, const Eigen::Vector3d& offset,
                                          double yaw, double pitch) const {
  return pivot - rot_y(yaw) * (rot_x(pitch) * offset);
}

Eigen::Vector3d FootGeometry::ankle_about_dpitch(const Eigen::Vector3d& offset, double yaw,
                                                 double pitch) const {
  // d/dp of rot_x(p) * v is (0, -vy sin p - vz cos p, vy cos p - vz sin p).
  const double c = std::cos(pitch), s = std::sin(pitch);
  const Eigen::Vector3d dv(0, -offset.y() * s - offset.z() * c, offset.y() * c - offset.z() * s);
  return -(rot_y(yaw) * dv);
}

FootGeometry::Points FootGeometry::points(const FootState& foot) const {
  const Eigen::Matrix3d Rf = rot_y(foot.yaw) * rot_x(foot.pitch);
  const Eigen::Matrix3d Rt = rot_y(foot.yaw) * rot_x(foot.toe_pitch);
  Points p;
  p.heel = foot.ankle + Rf * heel_offset_;
  p.ball = foot.ankle + Rf * ball_offset_;
  p.ball_sole = p.ball + Rt * ball_sole_offset_;
  p.toe_tip = p.ball + Rt * toe_tip_offset_;
  return p;
}

double FootGeometry::lowest(const FootState& foot) const {
  const Points p = points(foot);
  return std::min({p.heel.y(), p.ball_sole.y(), p.toe_tip.y()});
}

Eigen::Vector3d FootGeometry::heel_when_flat(const Eigen::Vector3d& ankle, double yaw) const {
  return ankle + rot_y(yaw) * heel_offset_;
}

Eigen::Vector3d FootGeometry::ball_when_flat(const Eigen::Vector3d& ankle, double yaw) const {
  return ankle + rot_y(yaw) * ball_offset_;
}

// ---------------------------------------------------------------------------------------------
// Pose writer

namespace {
const motion::RotationOrder kZxy{{2, 0, 1}, 3};

// Half of a rotation (same axis, half the angle); the rotations involved stay well below pi.
Eigen::Matrix3d half_rotation(const Eigen::Matrix3d& R) {
  Eigen::AngleAxisd aa(R);
  return Eigen::AngleAxisd(aa.angle() / 2, aa.axis()).toRotationMatrix();
}
}  // namespace

PoseWriter::PoseWriter(const Figure& figure)
    : figure_(figure),
      previous_(static_cast<std::size_t>(figure.skeleton->joint_count()), Eigen::Vector3d::Zero()) {}

Eigen::Vector3d PoseWriter::hip_world(const BodyPose& pose, Side side) const {
  return pose.root + pose.pelvis * figure_.skeleton->joint(figure_.up_leg[side]).offset;
}

double PoseWriter::leg_extension(const BodyPose& pose, Side side) const {
  return (pose.feet[side].ankle - hip_world(pose, side)).norm() / figure_.dims.leg_length();
}

Eigen::Vector3d two_link_middle(const Eigen::Vector3d& base, const Eigen::Vector3d& tip, double l1, double l2,
                                const Eigen::Vector3d& pole, double max_extension, double* reach) {
  const Eigen::Vector3d d = tip - base;
  const double D = d.norm();
  const double Dc = std::clamp(D, std::abs(l1 - l2) + 1e-6 * (l1 + l2), max_extension * (l1 + l2));
  const Eigen::Vector3d u = d / D;
  // In the plane of the base-tip line and the pole, on the pole's side.
  const Eigen::Vector3d side = (pole - pole.dot(u) * u).normalized();
  const double cos_a = std::clamp((l1 * l1 + Dc * Dc - l2 * l2) / (2 * l1 * Dc), -1.0, 1.0);
  if (reach) *reach = Dc;
  return base + l1 * (cos_a * u + std::sqrt(1 - cos_a * cos_a) * side);
}

Eigen::Vector3d PoseWriter::shoulder_world(const BodyPose& pose, Side side) const {
  const motion::Skeleton& sk = *figure_.skeleton;
  // As write() poses the trunk: Spine takes half the pelvis-to-chest rotation, Chest the rest,
  // the clavicle (Shoulder) none.
  const Eigen::Matrix3d spine_world = pose.pelvis * half_rotation(pose.pelvis.transpose() * pose.chest);
  const Eigen::Vector3d spine = pose.root + pose.pelvis * sk.joint(figure_.spine).offset;
  const Eigen::Vector3d chest = spine + spine_world * sk.joint(figure_.chest).offset;
  return chest + pose.chest * (sk.joint(figure_.shoulder[side]).offset + sk.joint(figure_.arm[side]).offset);
}

double PoseWriter::arm_extension(const BodyPose& pose, Side side) const {
  const auto& target = pose.hands[side];
  if (!target) return 0;
  return (target->wrist - shoulder_world(pose, side)).norm() /
         (figure_.dims.upper_arm + figure_.dims.forearm);
}

void PoseWriter::write_arm_ik(const BodyPose& pose, Side side, const HandTarget& target, double* frame) {
  const Figure& f = figure_;
  const motion::Skeleton& sk = *f.skeleton;
  const double L1 = f.dims.upper_arm, L2 = f.dims.forearm;
  const Eigen::Vector3d shoulder = shoulder_world(pose, side);
  const Eigen::Vector3d u = (target.wrist - shoulder).normalized();
  double Dc = 0;
  const Eigen::Vector3d elbow =
      two_link_middle(shoulder, target.wrist, L1, L2, target.elbow_pole, kMaxExtension, &Dc);
  // The upper arm's frame: its bone along -Y, the forearm bending towards its +Z (the elbow's
  // only channel is a flexion about X, like the knee's).
  Eigen::Matrix3d upper;
  upper.col(1) = (shoulder - elbow) / L1;
  const Eigen::Vector3d fore = (shoulder + Dc * u - elbow) / L2;
  upper.col(2) = (fore - fore.dot(upper.col(1)) * upper.col(1)).normalized();
  upper.col(0) = upper.col(1).cross(upper.col(2));
  const double flexion = std::atan2(fore.dot(upper.col(2)), -fore.dot(upper.col(1)));

  auto put_zero = [&](int joint) {
    const int c = sk.joint(joint).first_channel;
    frame[c] = frame[c + 1] = frame[c + 2] = 0;
    previous_[static_cast<std::size_t>(joint)] = Eigen::Vector3d::Zero();
  };
  put_zero(f.shoulder[side]);
  set_euler(f.arm[side], pose.chest.transpose() * upper, frame);
  const int ec = sk.joint(f.forearm[side]).first_channel;
  frame[ec] = 0;
  frame[ec + 1] = -flexion;
  frame[ec + 2] = 0;
  previous_[static_cast<std::size_t>(f.forearm[side])] = Eigen::Vector3d(0, -flexion, 0);
  set_euler(f.hand[side], (upper * rot_x(-flexion)).transpose() * target.hand, frame);
}

void PoseWriter::set_euler(int joint, const Eigen::Matrix3d& local, double* frame) {
  Eigen::Vector3d& prev = previous_[static_cast<std::size_t>(joint)];
  prev = motion::matrix_to_euler(local, kZxy, prev);
  const int c = figure_.skeleton->joint(joint).first_channel + (joint == figure_.hips ? 3 : 0);
  frame[c] = prev[0];
  frame[c + 1] = prev[1];
  frame[c + 2] = prev[2];
}

double PoseWriter::write(const BodyPose& pose, double* frame) {
  const Figure& f = figure_;
  const motion::Skeleton& sk = *f.skeleton;
  const int rc = sk.joint(f.hips).first_channel;
  frame[rc] = pose.root.x();
  frame[rc + 1] = pose.root.y();
  frame[rc + 2] = pose.root.z();
  set_euler(f.hips, pose.pelvis, frame);

  // The trunk's rotation shared equally by Spine and Chest, the head's by Neck and Head.
  const Eigen::Matrix3d spine_half = half_rotation(pose.pelvis.transpose() * pose.chest);
  set_euler(f.spine, spine_half, frame);
  set_euler(f.chest, spine_half.transpose() * pose.pelvis.transpose() * pose.chest, frame);
  const Eigen::Matrix3d neck_half = half_rotation(pose.chest.transpose() * pose.head);
  set_euler(f.neck, neck_half, frame);
  set_euler(f.head, neck_half.transpose() * pose.chest.transpose() * pose.head, frame);

  for (Side side : {kLeft, kRight}) {
    if (pose.hands[side]) {
      write_arm_ik(pose, side, *pose.hands[side], frame);
      continue;
    }
    const ArmPose& a = pose.arms[side];
    // Written straight as Z (abduction) X (flexion) Y (none): no decomposition, so an arm raised
    // past 90 degrees meets no Euler singularity.
    auto put = [&](int joint, double z, double x) {
      const int c = sk.joint(joint).first_channel;
      frame[c] = z;
      frame[c + 1] = x;
      frame[c + 2] = 0;
      previous_[static_cast<std::size_t>(joint)] = Eigen::Vector3d(z, x, 0);
    };
    put(f.shoulder[side], 0, 0);
    put(f.arm[side], side_sign(side) * a.abduction, -a.flexion);
    put(f.forearm[side], 0, -a.elbow);
    put(f.hand[side], 0, 0);
  }

  const double L1 = f.dims.thigh, L2 = f.dims.shank, L = L1 + L2;
  double worst = 0;
  for (Side side : {kLeft, kRight}) {
    const FootState& foot = pose.feet[side];
    const Eigen::Vector3d hip = hip_world(pose, side);
    const Eigen::Vector3d d = foot.ankle - hip;
    const double D = d.norm();
    worst = std::max(worst, D / L);
    const Eigen::Vector3d u = d / D;
    // The knee points where the foot and the pelvis head, in the plane through hip and ankle.
    Eigen::Vector3d forward = rot_y(foot.yaw) * Eigen::Vector3d::UnitZ();
    Eigen::Vector3d pelvis_forward = pose.pelvis * Eigen::Vector3d::UnitZ();
    pelvis_forward.y() = 0;
    forward += pelvis_forward.normalized();
    const Eigen::Vector3d pole = (forward - forward.dot(u) * u).normalized();
    double Dc = 0;
    const Eigen::Vector3d knee = two_link_middle(hip, foot.ankle, L1, L2, forward, kMaxExtension, &Dc);
    Eigen::Matrix3d thigh;
    thigh.col(1) = (hip - knee) / L1;
    thigh.col(2) = (pole - pole.dot(thigh.col(1)) * thigh.col(1)).normalized();
    thigh.col(0) = thigh.col(1).cross(thigh.col(2));
    // Knee flexion from the shank's direction in the thigh's frame: (0, -cos k, -sin k).
    const Eigen::Vector3d shank_dir = thigh.transpose() * ((hip + Dc * u - knee) / L2);
    const double knee_angle = std::atan2(-shank_dir.z(), -shank_dir.y());

    set_euler(f.up_leg[side], pose.pelvis.transpose() * thigh, frame);
    const int kc = sk.joint(f.leg[side]).first_channel;
    frame[kc] = 0;
    frame[kc + 1] = knee_angle;
    frame[kc + 2] = 0;
    previous_[static_cast<std::size_t>(f.leg[side])] = Eigen::Vector3d(0, knee_angle, 0);
    const Eigen::Matrix3d shank = thigh * rot_x(knee_angle);
    const Eigen::Matrix3d foot_world = rot_y(foot.yaw) * rot_x(foot.pitch);
    set_euler(f.foot[side], shank.transpose() * foot_world, frame);
    const int tc = sk.joint(f.toe[side]).first_channel;
    frame[tc] = 0;
    frame[tc + 1] = foot.toe_pitch - foot.pitch;
    frame[tc + 2] = 0;
  }
  return worst;
}

double write_frames(PoseWriter& writer, const Figure& figure, const std::function<BodyPose(double)>& pose_at,
                    int frames, double fps, const std::string& name, motion::Motion& motion) {
  motion.skeleton = figure.skeleton;
  motion.fps = fps;
  motion.name = name;
  motion.values.resize(frames, figure.skeleton->channel_count());
  double worst = 0;
  for (int f = 0; f < frames; ++f)
    worst = std::max(worst, writer.write(pose_at(f / fps), motion.values.row(f).data()));
  motion.check();
  return worst;
}

void PlantRecorder::add(Side side, FootPoint point, double t0, double t1, const Eigen::Vector3d& world) {
  const bool on_foot = point == FootPoint::Heel || point == FootPoint::Ankle;
  FootPlant plant;
  plant.side = side;
  plant.point = point;
  plant.joint = on_foot ? figure_.foot[side] : figure_.toe[side];
  plant.local = point == FootPoint::Heel    ? figure_.heel_local
                : point == FootPoint::Ankle ? figure_.ankle_local
                : point == FootPoint::Ball  ? figure_.ball_local
                                            : figure_.toe_tip_local;
  std::tie(plant.first_frame, plant.last_frame) = frame_span(t0, std::min(t1, t_end_), fps_);
  plant.world = world;
  if (plant.first_frame <= plant.last_frame) plants_.push_back(plant);
}

double root_height_for(const PoseWriter& writer, BodyPose pose, double extension, double lo, double hi) {
  for (int i = 0; i < 60; ++i) {
    pose.root.y() = (lo + hi) / 2;
    const double e = std::max(writer.leg_extension(pose, kLeft), writer.leg_extension(pose, kRight));
    (e <= extension ? lo : hi) = pose.root.y();
  }
  return lo;
}

std::pair<int, int> frame_span(double t0, double t1, double fps) {
  const double slack = 1e-7;  // frames
  return {static_cast<int>(std::ceil(t0 * fps - slack)), static_cast<int>(std::floor(t1 * fps + slack))};
}

void check_range(const char* what, const char* name, double value, double min, double max, const char* unit) {
  if (std::isfinite(value) && value >= min && value <= max) return;
  std::ostringstream s;
  s << "synthesize_" << what << ": " << name << " " << value << (*unit ? " " : "") << unit << ": expected "
    << min << " to " << max;
  throw std::invalid_argument(s.str());
}

}  // namespace kg::synth::detail
