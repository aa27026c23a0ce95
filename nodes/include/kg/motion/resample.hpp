// Rotation-safe sampling of a clip between its frames, and resampling to another frame rate
// (McCann et al. resampled 120 Hz captures to 30 Hz). Position channels are interpolated
// linearly. Each joint's rotation channels move together: with three rotation channels the two
// frames' rotations are slerped along the shorter arc and converted back to the joint's own Euler
// order: the Euler solution is the one nearest the two frames' own angles interpolated, so the
// curves are the input's (where an exporter switched solutions at gimbal lock between two
// frames, so does the result), and whole turns follow a reference (the previous output frame), so
// curves stay continuous through +-180 degrees. With one or two rotation channels each angle
// is interpolated along its shorter way round; for one channel that is exactly the slerp, and
// for two it stays inside the joint's two degrees of freedom, which a slerp would leave.
//
//   Motion m30 = resample(m120, 30.0);                 // frames = floor(duration * 30) + 1
//   Eigen::RowVectorXd pose = pose_at(m120, 0.51);     // the pose 0.51 s into the clip
#pragma once

#include <Eigen/Core>

#include "kg/motion/kinematics.hpp"
#include "kg/motion/motion.hpp"

namespace kg::motion {

// The frame between a and b (channel_count() values each, skeleton.hpp's units) at fraction
// u in [0, 1] (0 gives a, 1 gives b; values outside are clamped). Of a three-channel rotation,
// the Euler solution nearest a and b's angles interpolated, each angle then shifted by whole
// turns nearest `reference` (a frame of the same layout, usually the previous output); at
// u == 0 and u == 1 the source frame's angles are kept, shifted so too. `out` must not alias a or b; it may
// alias reference.
void interpolate_frames(const Skeleton& skeleton, FrameRef a, FrameRef b, double u, FrameRef reference,
                        Eigen::Ref<Eigen::RowVectorXd> out);

// The pose at `time` seconds from the first frame (clamped to [0, duration()]); frame f lies at
// f / fps. Within 1e-9 frames of a frame time the frame itself is used. Whole turns follow
// `reference`, or without one the closer of the two surrounding frames.
// Throws std::invalid_argument for a motion without frames or a non-finite time.
void pose_at(const Motion& motion, double time, FrameRef reference, Eigen::Ref<Eigen::RowVectorXd> out);
void pose_at(const Motion& motion, double time, Eigen::Ref<Eigen::RowVectorXd> out);
Eigen::RowVectorXd pose_at(const Motion& motion, double time);

// Frames of a clip of `frames` frames at `fps` resampled to `new_fps`: floor(duration * new_fps)
// + 1 (1e-9 frames of slack against rounding), so the resampled clip never runs past the end.
int resampled_frame_count(int frames, double fps, double new_fps);

// The clip at `new_fps` frames per second: output frame k is pose_at(k / new_fps) with the
// previous output frame as reference (the first one is frame 0 itself). Output frames at times
// that coincide with input frames (every 4th input frame for 120 -> 30) equal those frames, up to
// whole turns that keep angle curves continuous where the input wraps. Keeps skeleton and name.
// Throws std::invalid_argument for a non-positive or non-finite new_fps, a motion failing
// check(), or a result of more than 2^31 values.
Motion resample(const Motion& motion, double new_fps);

}  // namespace kg::motion
