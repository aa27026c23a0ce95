// Private pieces shared by the walk and jump synthesizers: C1 curves in time, the foot's rigid
// rolling geometry, the writer turning a world-space body pose into one frame of channels
// (two-link leg IK included), and the clip and foot plants built from them. Not installed; only
// nodes/synth/*.cpp include it.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "kg/synth/figure.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg::synth::detail {

// A piecewise polynomial of degree <= 5 in time, pieces appended in order and contiguous.
// Before the first piece it holds the first value, after the last the last value (slope 0).
class Curve {
 public:
  // Coefficients of powers of (t - t0).
  void add_poly(double t0, double t1, const std::array<double, 6>& c);
  // Cubic from (y0, slope m0) at t0 to (y1, m1) at t1.
  void add_hermite(double t0, double t1, double y0, double m0, double y1, double m1);
  // Quintic matching value, slope and second derivative at both ends.
  void add_quintic(double t0, double t1, double y0, double v0, double a0, double y1, double v1, double a1);
  void add_hold(double t0, double t1, double y) { add_poly(t0, t1, {y, 0, 0, 0, 0, 0}); }

  double value(double t) const;
  double slope(double t) const;
  double second(double t) const;
  bool empty() const { return pieces_.empty(); }
  double end_time() const { return pieces_.back().t1; }

 private:
  struct Piece {
    double t0, t1;
    std::array<double, 6> c;
  };
  const Piece* find(double t) const;
  std::vector<Piece> pieces_;
};

// Keys (time, value) in increasing time joined by cubic Hermite pieces with Fritsch-Carlson
// slopes: no overshoot between keys, zero slope at every local extremum and at both ends.
Curve monotone_curve(const std::vector<std::pair<double, double>>& keys);

// A cubic Hermite in three dimensions.
Eigen::Vector3d hermite(const Eigen::Vector3d& y0, const Eigen::Vector3d& m0, const Eigen::Vector3d& y1,
                        const Eigen::Vector3d& m1, double h, double s);
double hermite(double y0, double m0, double y1, double m1, double h, double s);
double hermite_slope(double y0, double m0, double y1, double m1, double h, double s);

inline Eigen::Matrix3d rot_x(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
inline Eigen::Matrix3d rot_y(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
inline Eigen::Matrix3d rot_z(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// A foot's pose in the world: ankle centre, heading (yaw about +Y, toes out positive on the left),
// pitch of the foot about its own lateral axis (positive = heel up, toes down) and the world
// pitch of the toe segment (0 = flat). The foot's world rotation is rot_y(yaw) * rot_x(pitch).
struct FootState {
  Eigen::Vector3d ankle = Eigen::Vector3d::Zero();
  double yaw = 0;
  double pitch = 0;
  double toe_pitch = 0;
};

// Rigid rolling of the foot about points fixed on it (figure.hpp's landmarks).
class FootGeometry {
 public:
  explicit FootGeometry(const Figure& figure);
  // The ball joint's offset from the ankle in the foot's frame (ToeBase's OFFSET).
  const Eigen::Vector3d& ball_offset() const { return ball_offset_; }
  const Eigen::Vector3d& heel_offset() const { return heel_offset_; }
  // Ankle centre for a foot pivoting about its heel point / ball joint held at `pivot` (world).
  Eigen::Vector3d ankle_about(const Eigen::Vector3d& pivot, const Eigen::Vector3d& offset, double yaw,
                              double pitch) const;
  // d(ankle_about) / d(pitch).
  Eigen::Vector3d ankle_about_dpitch(const Eigen::Vector3d& offset, double yaw, double pitch) const;
  // World positions of the heel point, ball joint, sole under the ball, and toe tip.
  struct Points {
    Eigen::Vector3d heel, ball, ball_sole, toe_tip;
  };
  Points points(const FootState& foot) const;
  // Lowest height of the heel, sole under the ball and toe tip.
  double lowest(const FootState& foot) const;
  // Flat foot whose ankle is at `ankle`: where its heel point and ball joint are.
  Eigen::Vector3d heel_when_flat(const Eigen::Vector3d& ankle, double yaw) const;
  Eigen::Vector3d ball_when_flat(const Eigen::Vector3d& ankle, double yaw) const;

 private:
  Eigen::Vector3d heel_offset_, ball_offset_, toe_tip_offset_, ball_sole_offset_;
};

struct ArmPose {
  double abduction = 0;  // outward, about the chest's forward axis
  double flexion = 0;    // forward swing (negative: backward)
  double elbow = 0;      // flexion, forearm forward
};

// An arm placed by two-link IK instead of angles: the hand's world rotation and where its wrist
// (the Hand joint) must be, world metres; the elbow bends towards `elbow_pole` (a world
// direction, not along the shoulder-wrist line). A point p of the hand then lies at
// wrist + hand * p exactly while the wrist is within reach.
struct HandTarget {
  Eigen::Vector3d wrist = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hand = Eigen::Matrix3d::Identity();
  Eigen::Vector3d elbow_pole = -Eigen::Vector3d::UnitY();
};

// Everything that fixes one frame, in world terms except the arms.
struct BodyPose {
  Eigen::Vector3d root = Eigen::Vector3d::Zero();
  Eigen::Matrix3d pelvis = Eigen::Matrix3d::Identity();  // world rotation of Hips
  Eigen::Matrix3d chest = Eigen::Matrix3d::Identity();   // world rotation of Chest (Spine takes half)
  Eigen::Matrix3d head = Eigen::Matrix3d::Identity();    // world rotation of Head (Neck takes half)
  std::array<ArmPose, 2> arms{};
  std::array<std::optional<HandTarget>, 2> hands{};  // when set, replaces arms[side]
  std::array<FootState, 2> feet{};
};

// Two-link IK: where the middle joint (knee, elbow) of a chain from `base` (hip, shoulder) to
// `tip` (ankle, wrist) of link lengths l1, l2 lies, bending towards `pole` (a direction not along
// base-tip). A tip beyond max_extension (l1 + l2) or nearer than |l1 - l2| is reached as far
// as it can be along the same line; `reach` (not null) gets the clamped base-tip distance.
Eigen::Vector3d two_link_middle(const Eigen::Vector3d& base, const Eigen::Vector3d& tip, double l1, double l2,
                                const Eigen::Vector3d& pole, double max_extension, double* reach = nullptr);

// Turns body poses into frames, keeping the previous frame's Euler angles so each joint's angles
// take the branch nearest them (continuity across frames).
class PoseWriter {
 public:
  explicit PoseWriter(const Figure& figure);
  // Hip-to-ankle distance over thigh + shank for one leg of `pose`.
  double leg_extension(const BodyPose& pose, Side side) const;
  // Shoulder (Arm joint) to wrist target distance over upper arm + forearm; 0 without a target.
  double arm_extension(const BodyPose& pose, Side side) const;
  // World position of the Arm joint (the shoulder) of `pose`.
  Eigen::Vector3d shoulder_world(const BodyPose& pose, Side side) const;
  // Writes the frame (skeleton channel layout). Returns the larger leg extension of the two legs;
  // legs (and arms with a target) beyond kMaxExtension are solved at kMaxExtension (the caller
  // checks the return value and arm_extension).
  double write(const BodyPose& pose, double* frame);

  static constexpr double kMaxExtension = 0.9995;

 private:
  Eigen::Vector3d hip_world(const BodyPose& pose, Side side) const;
  void set_euler(int joint, const Eigen::Matrix3d& local, double* frame);
  void write_arm_ik(const BodyPose& pose, Side side, const HandTarget& target, double* frame);

  const Figure& figure_;
  std::vector<Eigen::Vector3d> previous_;  // per joint, ZXY angles of the previous frame
};

// Fills `motion` with `frames` frames of the poses pose_at(f / fps) (the figure's skeleton, fps,
// `name`) through `writer`, and checks it. Returns the largest leg extension writer.write met.
double write_frames(PoseWriter& writer, const Figure& figure, const std::function<BodyPose(double)>& pose_at,
                    int frames, double fps, const std::string& name, motion::Motion& motion);

// Appends the foot plants of a clip of `frames` frames at `fps` to `plants`: each a point held at
// `world` (metres) from t0 to t1 (seconds), cut at the last frame and dropped when that span holds
// no frame. Heel and ankle are points of the foot joint, ball and toe tip of the toe joint (the
// Figure's landmarks).
class PlantRecorder {
 public:
  PlantRecorder(const Figure& figure, double fps, int frames, std::vector<FootPlant>& plants)
      : figure_(figure), fps_(fps), t_end_((frames - 1) / fps), plants_(plants) {}
  void add(Side side, FootPoint point, double t0, double t1, const Eigen::Vector3d& world);

 private:
  const Figure& figure_;
  double fps_, t_end_;
  std::vector<FootPlant>& plants_;
};

// Largest root height in [lo, hi] (bisection, all else fixed) at which both legs of `pose` reach
// with at most `extension` of their length; lo when none.
double root_height_for(const PoseWriter& writer, BodyPose pose, double extension, double lo, double hi);

// Frame span [first, last] of the times [t0, t1] at `fps` (inclusive; empty when first > last).
std::pair<int, int> frame_span(double t0, double t1, double fps);

// Throws std::invalid_argument "synthesize_<what>: <name> <value> <unit>: expected <min> to <max>".
void check_range(const char* what, const char* name, double value, double min, double max, const char* unit);

}  // namespace kg::synth::detail
