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
// How (jump): stand, countermovement crouch, push-off onto the balls of the feet, a flight in which
// the root's height is exactly y(t) = y0 + v0 t - g t^2 / 2 and its forward position linear,
// landing on the balls of both feet, heels down, absorbing crouch, stand. Root curves are quintic
// in the ground phases, matching position, velocity and acceleration (-g) at takeoff and landing.
// The takeoff and landing leg geometry (the body leans with the forward speed) fixes the takeoff
// and landing heights, hence the flight time and the forward speed; feet leave and land at rest,
// and in between move relative to the root (tucked at 45 % of the flight). The root's height
// and forward position are ballistic; its orientation is not (the trunk keeps moving).
//
// Conventions: metres, radians, seconds; world +Y up, floor y = 0, the figure walks and jumps
// along world +Z, its left on +X. Frame f lies at time f / fps.
//
//   Synthesis walk = synthesize_walk({.steps = 6, .speed = 1.3});
//   const motion::Motion& m = walk.motion;                 // 66 channels at 120 fps
//   for (const FootPlant& p : walk.plants) ...            // frames during which a point stays put
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
inline constexpr Range kStepsRange{2, 200};           // steps of a walk
inline constexpr Range kSpeedRange{0.4, 2.0};         // walking speed, m/s
inline constexpr Range kStatureRange{1.2, 2.2};       // m
inline constexpr Range kFpsRange{10, 1000};           // frames per second
inline constexpr Range kJumpHeightRange{0.05, 0.6};   // rise of the root from takeoff to apex, m
inline constexpr Range kJumpDistanceRange{0.0, 2.0};  // forward travel of the feet, m
inline constexpr Range kGravityRange{1.0, 30.0};      // m/s^2

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

struct Synthesis {
  motion::Motion motion;  // skeleton = figure.skeleton
  Figure figure;
  std::vector<FootPlant> plants;  // ordered by side, then time, then point
  int steps = 0;                  // walk: foot landings (heel strikes); jump: 0
  GaitParameters gait;            // walk only
  // Seconds. Walk: first and last heel strike of the steady part (pelvis moving at exactly `speed`
  // between them; empty span for fewer than 3 steps). Jump: takeoff and touchdown.
  double steady_start = 0, steady_end = 0;
  double flight_start = 0, flight_end = 0;  // jump: takeoff and landing; walk: 0
  double takeoff_velocity_up = 0;           // jump: root's vertical velocity at takeoff, m/s
  double takeoff_velocity_forward = 0;      // jump: root's forward (+Z) velocity, m/s
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
};

struct JumpOptions {
  double height = 0.3;    // rise of the root from takeoff to the apex, m
  double distance = 0.8;  // forward travel of the feet from takeoff to landing, m (0: vertical
                          // jump; its root drifts about 2 cm back in flight, the leans differing)
  double stature = 1.75;  // m
  double fps = 120;
  double gravity = 9.81;  // m/s^2
};

// Both throw std::invalid_argument naming the parameter, its value and its range when an option
// is out of range or not finite; synthesize_jump also when the distance needs a forward takeoff
// speed over twice the upward one (a long, low jump no standing jumper makes, e.g. 2 m at 0.1 m).
// std::logic_error would mean a plan the code cannot realise (none is known in the ranges).
Synthesis synthesize_walk(const WalkOptions& options);
Synthesis synthesize_jump(const JumpOptions& options);

}  // namespace kg::synth
