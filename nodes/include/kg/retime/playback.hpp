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

// The warp played past its end: p, ṗ and p̈ at output time t, and beyond warp.duration the
// warp's end speed held (p = source_duration + (t - duration) ṗ(duration), p̈ = 0). A clip played
// at a finer rate than the retiming worked at outlasts the warp's source by up to one frame of
// the working rate (3.617 s at 120 Hz is 3.6 s at 30): its last poses play so.
WarpSample played_sample(const TimeWarp& warp, double t);
// The output seconds that play a clip of `source_duration` (>= the warp's): warp.duration plus
// the tail at the end speed.
double played_duration(const TimeWarp& warp, double source_duration);

// Output frames at times k / fps, k = 0 .. floor(played_duration * fps + 1e-9) (the last frame is
// the source's last pose when that duration is a whole number of frames); frame k is the source
// pose at p(k / fps) (played_sample: positions linear, rotations slerped and continuous with the
// previous frame). Keeps the skeleton; the name gains nothing. Throws std::invalid_argument for
// fps <= 0 (or too many frames, output_frame_count), a motion failing check(), or a warp whose
// source duration differs from the clip's by more than `slack` seconds (negative: half a frame
// of the clip). A clip played at a finer rate than the retiming worked at may outlast the warp's
// source by up to one frame of the working rate: pass that frame as the slack.
motion::Motion retimed_motion(const motion::Motion& source, const TimeWarp& warp, double fps,
                              double slack = -1);

// One row per output frame at `fps`: t,p,pdot,pddot (seconds, source seconds, per second, per
// second²; played_sample), with a header line; `frames` rows (negative: output_frame_count's), so
// the curves of a clip played past the warp's end have a row per frame written.
void write_warp_csv(std::ostream& os, const TimeWarp& warp, double fps, int frames = -1);
// {"duration": s, "source_duration": s, "fps": f, "controls": [...], "t": [...], "p": [...],
//  "pdot": [...], "pddot": [...]} with the same rows as the CSV.
void write_warp_json(std::ostream& os, const TimeWarp& warp, double fps, int frames = -1);

}  // namespace kg::retime
