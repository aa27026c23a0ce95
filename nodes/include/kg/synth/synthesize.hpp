// Synthesized human motion: a walk and a standing jump on the figure of figure.hpp, with feet
// planted exactly on the floor, so that pipelines and tests run with no captured data.
//
// How (walk): footprints are placed first from a gait relation; each foot then rolls through its
// stance (heel strike -> foot flat -> heel off -> toe off) by rotating rigidly about the heel
// point, then lying flat, then rotating about the ball joint with the toes flat on the floor, and
// swings between footprints along C1 Hermite curves lifted clear of the floor. The pelvis follows
// smooth curves (forward progress, vertical bob, lateral sway, rotation, list), its height set
// as high as the planted legs reach with at most 0.998 of their length; each leg is then solved
// by analytic two-link IK (hip-knee-ankle, knee pointing forward) and the foot and toe angles
// follow from the feet's world orientations. A swinging foot whose target would stretch its leg
// further (just after toe off at high speed) is drawn smoothly towards the hip. Every curve is
// at least C1 in time, so every channel is. The walk starts standing with the feet side by side
// (ankles at z = 0), the right foot steps first, and the last step brings the trailing foot
// alongside; the pelvis accelerates to `speed` over the first step time and stops as the last
// foot lands.
//
// How (jump): stand, countermovement crouch, push-off onto the balls of the feet, a flight, landing
// on the balls of both feet, heels down, absorbing crouch, stand. The plan's root flies
// y(t) = y0 + v0 t - g t^2 / 2, forward position linear; root curves are quintic in the ground
// phases, matching position, velocity and acceleration (-g) at takeoff and landing. The takeoff
// and landing leg geometry (the body leans with the forward speed) fixes the takeoff and landing
// heights, hence the flight time and the forward speed; feet leave and land at rest, and in
// between move relative to the root (tucked at 45 % of the flight). Since the limbs move about the
// root, the flying body is then shifted rigidly so that its centre of mass (retime.body_model's
// default mass model, de Leva's male table) follows the ballistic parabola through its takeoff and
// touchdown positions exactly, the shift fading in and out within the flight's first and last 15 %
// (at most 0.04 s). Its orientation is not ballistic (the trunk keeps moving).
//
// How (climb, Gleicher 1998 7.2 has a ladder clip; we have none): a vertical ladder stands in the
// plane z = ladder_distance in front of the figure, rungs every rung_spacing metres (the first one
// rung_spacing above the floor), rails at x = +-rail_half_width. The figure starts standing on
// the first rung with both hands on the rails and climbs `rungs` rungs one limb at a time (three
// points always hold): a hand lets go, reaches higher up its rail and grips again, then the foot
// of the other side steps up, the body rising as it swings. The feet alternate and pass
// each other (each step two rungs, the first and last one rung, so the climb ends with both feet
// on one rung), as do the hands. Every hold is exact: the sole under the ball of a foot lies on
// the top line of its rung, the middle of a hand's grip on its rail's centre line, fixed in the
// world while held (a foot keeps its world orientation; a hand turns about its grip point with
// the arm, so the wrist only flexes). Limbs move between holds on C1 paths that leave and arrive
// at rest (a foot pulls back behind the rungs, rises and comes down onto its rung from above),
// the root rises on quintics while a foot swings; legs and arms are solved by analytic two-link
// IK (knees forward, elbows down and out), so every channel is C1. The pelvis rides as high
// above the feet as lets the most stretched leg reach 0.93 of its length; the grips sit at the
// height that stretches the arms least (a grip passes from above the shoulder to below it while
// held).
//
// Conventions: metres, radians, seconds; world +Y up, floor y = 0, the figure walks and jumps
// along world +Z (and faces the ladder along +Z), its left on +X. Frame f lies at time f / fps.
//
//   Synthesis walk = synthesize_walk({.steps = 6, .speed = 1.3});
//   const motion::Motion& m = walk.motion;                 // 66 channels at 120 fps
//   for (const FootPlant& p : walk.plants) ...            // frames during which a point stays put
//   Synthesis climb = synthesize_climb({.rungs = 4, .fps = 30});
//   for (const Hold& h : climb.holds) ...                 // a foot on a rung, a hand on a rail
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"
#include "kg/synth/figure.hpp"

namespace kg::synth {

// Inclusive ranges of the synthesizer's parameters; the node `motion.synthesize` declares the same.
struct Range {
  double min, max;
};
inline constexpr Range kStepsRange{2, 200};              // steps of a walk
inline constexpr Range kSpeedRange{0.4, 2.0};            // walking speed, m/s
inline constexpr Range kStatureRange{1.2, 2.2};          // m
inline constexpr Range kFpsRange{10, 1000};              // frames per second
inline constexpr Range kJumpHeightRange{0.05, 0.6};      // the planned root's rise to the apex, m
inline constexpr Range kJumpDistanceRange{0.0, 2.0};     // forward travel of the feet, m
inline constexpr Range kGravityRange{1.0, 30.0};         // m/s^2
inline constexpr Range kClimbRungsRange{1, 60};          // rungs climbed
inline constexpr Range kRungSpacingRange{0.2, 0.4};      // m between rungs (and floor to rung 1)
inline constexpr Range kRailHalfWidthRange{0.15, 0.35};  // m from the ladder's middle to a rail
inline constexpr Range kLadderDistanceRange{0.25, 0.7};  // m from the root's line to the ladder

// Step length and timing from speed and stature, by the "walk ratio" relation (Sekiya & Nagasaki
// 1998: step length / cadence is nearly constant across speeds, about 0.0065 m per step/min for
// adult men of 1.70-1.75 m, taken here as 0.0037 H). cadence = sqrt(speed / ratio), step_length =
// speed / cadence. The stance fraction of a stride falls with speed (0.62 at 1 m/s, Perry's 60 %
// near 1.4 m/s), leaving a double support of (2 stance_fraction - 1) step_time per step.
struct GaitParameters {
  double speed = 0;            // m/s
  double step_length = 0;      // m, one foot's landing to the other's
  double step_time = 0;        // s per step (1 / cadence)
  double stance_fraction = 0;  // fraction of a stride (two steps) a foot is on the ground
  double stance_time() const { return 2 * step_time * stance_fraction; }
  double swing_time() const { return 2 * step_time - stance_time(); }
  double double_support_time() const { return stance_time() - step_time; }
};
// Throws std::invalid_argument for speed or stature outside kSpeedRange / kStatureRange.
GaitParameters gait_from_speed(double speed, double stature);

enum class FootPoint { Heel, Ankle, Ball, Toe };
const char* to_string(FootPoint point);  // "Heel", "Ankle", "Ball", "Toe"

// A point of a foot that stays fixed in the world over a span of frames (heel and ankle from
// heel strike / foot flat to heel off, ball and toe tip from foot flat to toe off).
struct FootPlant {
  Side side = kLeft;
  FootPoint point = FootPoint::Heel;
  int joint = -1;            // the segment the point is fixed on (foot[] or toe[])
  Eigen::Vector3d local;     // the point in that joint's frame, metres
  int first_frame = 0;       // inclusive
  int last_frame = 0;        // inclusive
  Eigen::Vector3d world;     // where it stays, metres, world frame
  std::string name() const;  // "LeftHeel", "RightToe", ...
};

// The climb's ladder, world metres: a vertical ladder in the plane z = distance (the plane of the
// rung tops and the rails' centre lines). Rung k (1 ... rung_count) is the segment of its top line
// from rail to rail at height k * rung_spacing: a foot stands on it. The rails run from the floor
// to rail_top at x = -+rail_half_width (right, left).
struct Ladder {
  double rung_spacing = 0;
  double rail_half_width = 0;
  double distance = 0;
  double rung_radius = 0;  // the rungs' round section, for clearance (its top is the rung line)
  int rung_count = 0;
  double rail_top = 0;
  double rung_height(int k) const { return k * rung_spacing; }
  // Ends A (right rail, -X) and B (left rail, +X) of rung k's top line.
  Eigen::Vector3d rung_a(int k) const { return {-rail_half_width, rung_height(k), distance}; }
  Eigen::Vector3d rung_b(int k) const { return {rail_half_width, rung_height(k), distance}; }
  // Ends A (at the floor) and B (at rail_top) of a rail's centre line.
  Eigen::Vector3d rail_a(Side side) const { return {side_sign(side) * rail_half_width, 0, distance}; }
  Eigen::Vector3d rail_b(Side side) const { return {side_sign(side) * rail_half_width, rail_top, distance}; }
};

// A point of a hand or foot held fixed in the world over a span of frames: a foot on a rung
// (`rung` >= 1; the point is the sole under the ball of the foot, on toe[]) or a hand on its
// rail (`rung` = 0; the middle of the grip, on hand[]). The point lies exactly on the segment
// from segment_a to segment_b (the rung's top line or the rail's centre line).
struct Hold {
  Side side = kLeft;
  bool hand = false;
  int rung = 0;                          // foot: 1-based rung index; hand: 0
  int joint = -1;                        // the segment the point is fixed on (toe[] or hand[])
  Eigen::Vector3d local;                 // the point in that joint's frame, metres
  int first_frame = 0;                   // inclusive
  int last_frame = 0;                    // inclusive
  Eigen::Vector3d world;                 // where it stays, metres, world frame
  Eigen::Vector3d segment_a, segment_b;  // the rung or rail it lies on, world metres
  std::string name() const;              // "LeftFoot on rung 3", "RightHand on the right rail at 1.90 m"
};

struct Synthesis {
  motion::Motion motion;  // skeleton = figure.skeleton
  Figure figure;
  std::vector<FootPlant> plants;  // ordered by side, then time, then point (climb: none)
  int steps = 0;                  // walk: foot landings (heel strikes); jump: 0; climb: rungs climbed
  std::vector<Hold> holds;        // climb: ordered by hands then feet, side, time; others: none
  Ladder ladder;                  // climb only
  double max_arm_extension = 0;   // climb: largest shoulder-to-wrist distance over the arm's length
  GaitParameters gait;            // walk only
  // Seconds. Walk: first and last heel strike of the steady part (pelvis moving at exactly `speed`
  // between them; empty span for fewer than 3 steps). Jump: takeoff and touchdown.
  double steady_start = 0, steady_end = 0;
  double flight_start = 0, flight_end = 0;  // jump: takeoff and landing; walk: 0
  double takeoff_velocity_up = 0;           // jump: the plan's root vertical velocity at takeoff, m/s
  double takeoff_velocity_forward = 0;      // jump: the plan's root forward (+Z) velocity, m/s
  double gravity = 0;                       // jump: m/s^2
  // Largest hip-to-ankle distance over the legs' full length (thigh + shank) in any frame; below
  // 1, so the knee never locks straight (the IK stays smooth).
  double max_leg_extension = 0;
};

struct WalkOptions {
  int steps = 8;          // foot landings, kStepsRange: the first starts from standing with the
                          // feet side by side, the last brings the trailing foot alongside
  double speed = 1.3;     // steady walking speed, m/s (start and stop ramp to and from rest)
  double stature = 1.75;  // m
  double fps = 120;       // frames per second
  // Throws std::invalid_argument naming the option, its value and its range (the k*Range
  // constants above) when one is out of range or not finite; node factories call it at load.
  void validate() const;
};

struct JumpOptions {
  double height = 0.3;    // rise of the planned root from takeoff to the apex, m (the shift that
                          // makes the centre of mass ballistic lowers the written root's apex
                          // by a few percent: 0.287 m for 0.3)
  double distance = 0.8;  // forward travel of the feet from takeoff to landing, m (0: vertical
                          // jump; its root drifts about 2 cm back in flight, the leans differing)
  double stature = 1.75;  // m
  double fps = 120;
  double gravity = 9.81;  // m/s^2
  // Throws std::invalid_argument naming the option, its value and its range (the k*Range
  // constants above) when one is out of range or not finite; node factories call it at load.
  void validate() const;
};

struct ClimbOptions {
  int rungs = 4;                  // rungs climbed, kClimbRungsRange
  double rung_spacing = 0.30;     // m, also the first rung's height above the floor
  double rail_half_width = 0.22;  // m, rails at x = +-this
  double ladder_distance = 0.50;  // m, the ladder plane's distance ahead of the root's line (z = 0)
  double stature = 1.75;          // m
  double fps = 120;
  // Throws std::invalid_argument naming the option, its value and its range (the k*Range
  // constants above) when one is out of range or not finite; node factories call it at load.
  void validate() const;
};

// All throw std::invalid_argument naming the parameter, its value and its range when an option
// is out of range or not finite; synthesize_jump also when the distance needs a forward takeoff
// speed over twice the upward one (a long, low jump no standing jumper makes, e.g. 2 m at 0.1 m);
// synthesize_climb also when the figure cannot span the ladder, saying which option and why:
// rungs too far apart for its legs, the ladder too far for its legs or arms, or so close that its
// elbows fold shut or its knees pass through the rungs. std::logic_error would mean a plan
// the code cannot realise (none is known in the ranges).
Synthesis synthesize_walk(const WalkOptions& options);
Synthesis synthesize_jump(const JumpOptions& options);
Synthesis synthesize_climb(const ClimbOptions& options);

}  // namespace kg::synth
