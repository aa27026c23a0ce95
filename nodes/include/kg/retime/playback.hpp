// Playing a clip through a retiming: the output motion at a frame rate (rotation-safe, via
// motion::pose_at), and the warp's curves p(t) and ṗ(t) as CSV or JSON for plots and other tools.
//
//   Motion fast = retimed_motion(jump, warp, 30.0);      // frames at k / 30 s play p(k / 30)
//   write_warp_csv(std::cout, warp, 30.0);                // t,p,pdot,pddot per output frame
#pragma once

#include <ostream>

#include "kg/motion/motion.hpp"
#include "kg/retime/timewarp.hpp"

namespace kg::retime {

// The frames a playback of `warp` at `fps` has: floor(warp.duration * fps + 1e-9) + 1. Throws
// std::invalid_argument for fps <= 0 or not finite, or more than kMaxOutputFrames frames.
inline constexpr int kMaxOutputFrames = 10'000'000;
int output_frame_count(const TimeWarp& warp, double fps);

// Output frames at times k / fps, k = 0 .. floor(warp.duration * fps + 1e-9) (the last frame is
// the source's last pose when the duration is a whole number of frames); frame k is the source
// pose at p(k / fps) (positions linear, rotations slerped and continuous with the previous
// frame). Keeps the skeleton; the name gains nothing. Throws std::invalid_argument for fps <= 0
// (or too many frames, output_frame_count),
// a motion failing check(), or a warp whose source duration differs from the clip's by more
// than `slack` seconds (negative: half a frame of the clip). A clip played at a finer rate than
// the retiming worked at may outlast the warp's source by up to one frame of the working rate:
// then pass that frame as the slack; its last poses after p's end are not played.
motion::Motion retimed_motion(const motion::Motion& source, const TimeWarp& warp, double fps,
                              double slack = -1);

// One row per output frame at `fps`: t,p,pdot,pddot (seconds, source seconds, per second, per
// second²), with a header line.
void write_warp_csv(std::ostream& os, const TimeWarp& warp, double fps);
// {"duration": s, "source_duration": s, "fps": f, "controls": [...], "t": [...], "p": [...],
//  "pdot": [...], "pddot": [...]} with the same rows as the CSV.
void write_warp_json(std::ostream& os, const TimeWarp& warp, double fps);

}  // namespace kg::retime
