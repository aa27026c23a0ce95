// Times read from files as frames of a clip, range-checked before any cast to int.
//
//   int f = seconds_to_frame(1.25, 30.0, 60);  // 38 (lround(37.5))
//   double fps = rate_of_printed_frame_time("0.0333333", 0.0333333);  // 30, not 30.00003
#pragma once

#include <string_view>

namespace kg::motion {

// The frame nearest `seconds` in a clip of `frame_count` frames at `fps` (> 0): lround(seconds *
// fps), range-checked in double before the cast, so a time read from a file can neither overflow
// int nor wrap into the clip. Throws std::out_of_range saying "<seconds> s is outside the clip
// (0..<duration> s, frames 0..<last> at <fps> fps)" for a time that is not finite, is negative, or
// rounds past the last frame. File readers catch it and rethrow at the time's file:line:column.
int seconds_to_frame(double seconds, double fps, int frame_count);

// The frame rate (per second) a frame time printed as `printed` (its parsed value `seconds`, > 0)
// stands for. A header prints 1/fps to a few digits ("0.0333333", "0.008333"), so 1/seconds is a
// little off the capture's rate (30.00003, 120.0048) and a clip resampled to its own rate would
// lose its last frame. When an integer rate n or an NTSC rate n * 1000/1001 prints as `printed`
// (1/rate lies within half a unit of its last digit) and those digits fix the rate to 1e-4 (so a
// short "0.03" stays 33.33), that rate; otherwise 1/seconds.
double rate_of_printed_frame_time(std::string_view printed, double seconds);

}  // namespace kg::motion
