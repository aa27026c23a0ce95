// The synthetic human figure: a CMU-like skeleton whose proportions follow a stature, so that the
// synthesizer (synthesize.hpp) and its tests have a body to move without any captured data.
//
// Layout (rest pose = all rotation channels zero): standing upright, facing world +Z, +Y up, the
// figure's left on +X, arms hanging at the sides, feet flat with the soles on the floor y = 0 and
// the toe tips touching it. Every rotation channel list is Zrotation Xrotation Yrotation (BVH's
// common ZXY); the root Hips also has Xposition Yposition Zposition first (metres).
//
//   Hips (root, 6 channels) -> Spine -> Chest -> Neck -> Head [End Site: top of head]
//   Chest -> LeftShoulder (clavicle) -> LeftArm -> LeftForeArm -> LeftHand [End Site: fingertip]
//   Chest -> RightShoulder -> RightArm -> RightForeArm -> RightHand [End Site]
//   Hips -> LeftUpLeg -> LeftLeg -> LeftFoot (ankle) -> LeftToeBase (ball) [End Site: toe tip]
//   Hips -> RightUpLeg -> RightLeg -> RightFoot -> RightToeBase [End Site]
//
// Segment lengths are fractions of stature H from the Drillis & Contini (1966) proportions as drawn
// by Winter (Biomechanics and Motor Control of Human Movement, fig. 4.1): ankle 0.039 H, knee
// 0.285 H, hip 0.530 H, shoulder 0.818 H above the floor; upper arm 0.186 H, forearm 0.146 H,
// hand 0.108 H, foot 0.152 H. Joints and end sites span exactly H from toe tip to top of head.
//
//   Figure fig = make_figure(1.75);
//   int ankle = fig.foot[kLeft];
//   Eigen::Vector3d heel = world[ankle] * fig.heel_local;   // a point fixed on the left foot
#pragma once

#include <array>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "kg/motion/skeleton.hpp"

namespace kg::synth {

enum Side : int { kLeft = 0, kRight = 1 };

// +1 for the left side (world +X in the rest pose), -1 for the right.
inline double side_sign(Side side) {
  return side == kLeft ? 1.0 : -1.0;
}
inline const char* side_name(Side side) {
  return side == kLeft ? "Left" : "Right";
}

// Lengths of the figure, metres, for a stature H (see the header comment for their sources).
struct FigureDimensions {
  double stature = 0;
  // Legs.
  double hip_height = 0;      // floor to hip joint centres, rest pose (0.530 H)
  double thigh = 0;           // hip to knee (0.245 H)
  double shank = 0;           // knee to ankle (0.246 H)
  double ankle_height = 0;    // floor to ankle centre with the foot flat (0.039 H)
  double hip_half_width = 0;  // pelvis centre to a hip joint, sideways (0.050 H)
  double pelvis_drop = 0;     // root (Hips) above the line of the hip joints (0.020 H)
  // Foot, in the foot's frame with the foot flat: heel behind the ankle, ball (metatarsophalangeal
  // joint = ToeBase) ahead of it, toe tip ahead of the ball. heel_back + ball_forward + toe_length
  // is the foot length 0.152 H.
  double heel_back = 0;     // 0.030 H
  double ball_forward = 0;  // 0.079 H
  double ball_height = 0;   // floor to the ball joint centre (0.012 H)
  double toe_length = 0;    // ball to toe tip (0.043 H)
  // Trunk, head: root -> Spine -> Chest -> Neck -> Head -> top, all straight up.
  double spine = 0;     // 0.040 H
  double chest = 0;     // 0.130 H
  double neck = 0;      // 0.115 H
  double head = 0;      // neck joint to head joint, 0.055 H
  double head_top = 0;  // head joint to the top of the head, 0.110 H
  // Arms: Chest -> Shoulder (clavicle) -> Arm (shoulder joint, 0.110 H off centre, 0.815 H high).
  double clavicle_side = 0;  // 0.020 H
  double clavicle_up = 0;    // 0.080 H
  double shoulder_side = 0;  // 0.090 H
  double shoulder_up = 0;    // 0.015 H
  double upper_arm = 0;      // 0.186 H
  double forearm = 0;        // 0.146 H
  double hand = 0;           // 0.108 H

  double leg_length() const { return thigh + shank; }
  double foot_length() const { return heel_back + ball_forward + toe_length; }
  // Root height above the floor in the rest pose.
  double rest_root_height() const { return hip_height + pelvis_drop; }
};

// Throws std::invalid_argument unless 0.5 <= stature <= 3 metres (the node's range is narrower).
FigureDimensions figure_dimensions(double stature);

// The skeleton and where things are on it. Joint indices refer to skeleton->joints().
struct Figure {
  std::shared_ptr<const motion::Skeleton> skeleton;
  FigureDimensions dims;

  int hips = -1, spine = -1, chest = -1, neck = -1, head = -1;
  std::array<int, 2> shoulder{-1, -1}, arm{-1, -1}, forearm{-1, -1}, hand{-1, -1};  // [kLeft], [kRight]
  std::array<int, 2> up_leg{-1, -1}, leg{-1, -1}, foot{-1, -1}, toe{-1, -1};

  // Points fixed on the feet, metres, in the named joint's frame (the same for both sides):
  Eigen::Vector3d heel_local;     // on foot[]: the bottom of the heel, on the floor when flat
  Eigen::Vector3d ankle_local;    // on foot[]: the ankle joint centre (zero)
  Eigen::Vector3d ball_local;     // on toe[]: the ball joint centre (zero; ToeBase's origin)
  Eigen::Vector3d toe_tip_local;  // on toe[]: the toe tip (the End Site), on the floor when flat
};

// The figure for `stature` metres; joint names as in the header comment. The root's OFFSET is its
// rest position (0, rest_root_height, 0); its position channels replace it. Throws like
// figure_dimensions.
Figure make_figure(double stature);

}  // namespace kg::synth
