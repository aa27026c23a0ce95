// Times read from files as frames of a clip, range-checked before any cast to int.
//
//   int f = seconds_to_frame(1.25, 30.0, 60);  // 38 (lround(37.5))
#pragma once

namespace kg::motion {

// The frame nearest `seconds` in a clip of `frame_count` frames at `fps` (> 0): lround(seconds *
// fps), range-checked in double before the cast, so a time read from a file can neither overflow
// int nor wrap into the clip. Throws std::out_of_range saying "<seconds> s is outside the clip
// (0..<duration> s, frames 0..<last> at <fps> fps)" for a time that is not finite, is negative, or
// rounds past the last frame. File readers catch it and rethrow at the time's file:line:column.
int seconds_to_frame(double seconds, double fps, int frame_count);

}  // namespace kg::motion
