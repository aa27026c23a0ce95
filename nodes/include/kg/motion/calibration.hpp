// Calibration frames: the pose an exporter puts before a clip's motion (a T-pose or A-pose as
// frame 0 of Daz and iClone exports, the rest pose some pipelines prepend). Such a prefix is no
// part of the performance: left in, retiming finds no playback speed inside its hulls at
// frame 0, and footplants and metrics see a body that jumps between poses in one frame.
//
//   CalibrationCut cut = detect_calibration_frames(motion);   // metres, world +Y (skeleton.hpp)
//   if (cut.frames > 0) motion.values = motion.values.bottomRows(motion.frame_count() - cut.frames);
//   log(cut.evidence);
#pragma once

#include <string>

#include "kg/motion/motion.hpp"

namespace kg::motion {

struct CalibrationCut {
  int frames = 0;        // frames 0..frames-1 are calibration frames (0: none)
  std::string evidence;  // one line for the user: the steps measured and the rule that decided
};

// The rule, from physics rather than from one clip: a body does not change its shape by much
// in one frame. Its shape is its joints' world positions about their centroid (metres; where it
// stands and how far it travels do not count); a step's speed is the RMS over joints of the
// change of shape into frame f, times fps. Take the fastest step of the clip's first half, the
// run of steps around it faster than a third of it (a jump, or an exporter's few-frame blend out
// of the calibration pose) and the steps after that still faster than the 99th percentile of the
// steps after them, taken again as they extend (the blend's ease-out: no clock enters, so a
// wrong frame rate moves no frame); the frames before the last of these are calibration frames when
//   - the peak is faster than kCalibrationSpeed (4 m/s RMS: a sprint's joints stay under 3,
//     a T-pose's arms dropping in one 30 Hz frame move 10 to 25),
//   - it is over kCalibrationRatio (3) times the later steps' 99th percentile (a clip's own
//     fastest motion is continuous: a wrong frame rate scales both sides alike, one glitch
//     frame later on does not count),
//   - the first kept frame lies in the first half, and
//   - the frames before the run hold one pose: none strays from frame 0 by over a third of the
//     change (a clip that starts moving, then glitches, keeps its frames).
inline constexpr double kCalibrationSpeed = 4.0;  // m/s
inline constexpr double kCalibrationRatio = 3.0;
CalibrationCut detect_calibration_frames(const Motion& motion);

}  // namespace kg::motion
