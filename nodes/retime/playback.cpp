#include "kg/retime/playback.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

#include "kg/base/json.hpp"
#include "kg/motion/resample.hpp"

namespace kg::retime {

namespace {

std::string shown(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

int frame_count(double duration, double fps) {
  if (!(fps > 0) || !std::isfinite(fps))
    throw std::invalid_argument("retimed playback: fps " + shown(fps) + " (expected > 0)");
  const double frames = std::floor(duration * fps + 1e-9) + 1;
  if (!(frames <= kMaxOutputFrames))
    throw std::invalid_argument("retimed playback: " + shown(duration) + " s at fps " + shown(fps) + " is " +
                                shown(frames) + " frames (expected at most " +
                                std::to_string(kMaxOutputFrames) + ")");
  return static_cast<int>(frames);
}

}  // namespace

int output_frame_count(const TimeWarp& warp, double fps) {
  return frame_count(warp.duration, fps);
}

WarpSample played_sample(const TimeWarp& warp, double t) {
  if (t <= warp.duration) return warp.sample(t);
  WarpSample s = warp.sample(warp.duration);
  s.p += (t - warp.duration) * s.pdot;
  s.pddot = 0;
  return s;
}

double played_duration(const TimeWarp& warp, double source_duration) {
  const double tail = source_duration - warp.source_duration;
  if (!(tail > 0)) return warp.duration;
  return warp.duration + tail / warp.sample(warp.duration).pdot;  // ṗ > 0: the warp increases
}

motion::Motion retimed_motion(const motion::Motion& source, const TimeWarp& warp, double fps, double slack) {
  source.check();
  if (std::abs(warp.source_duration - source.duration()) > (slack < 0 ? 0.5 / source.fps : slack) + 1e-9)
    throw std::invalid_argument("retimed playback: the warp plays " + std::to_string(warp.source_duration) +
                                " s of source but the clip '" + source.name + "' lasts " +
                                std::to_string(source.duration()) + " s");
  const int frames = frame_count(played_duration(warp, source.duration()), fps);
  motion::Motion out{source.skeleton, motion::FrameMatrix(frames, source.values.cols()), fps, source.name};
  for (int k = 0; k < frames; ++k) {
    const double p = std::min(played_sample(warp, k / fps).p, source.duration());
    if (k == 0)
      motion::pose_at(source, p, out.values.row(k));
    else
      motion::pose_at(source, p, out.values.row(k - 1), out.values.row(k));
  }
  return out;
}

void write_warp_csv(std::ostream& os, const TimeWarp& warp, double fps, int frames) {
  if (frames < 0) frames = output_frame_count(warp, fps);
  os << "t,p,pdot,pddot\n" << std::setprecision(10);
  for (int k = 0; k < frames; ++k) {
    const WarpSample s = played_sample(warp, k / fps);
    os << k / fps << ',' << s.p << ',' << s.pdot << ',' << s.pddot << '\n';
  }
}

void write_warp_json(std::ostream& os, const TimeWarp& warp, double fps, int frames) {
  if (frames < 0) frames = output_frame_count(warp, fps);
  std::vector<double> t, p, pdot, pddot;
  for (int k = 0; k < frames; ++k) {
    const WarpSample s = played_sample(warp, k / fps);
    t.push_back(k / fps), p.push_back(s.p), pdot.push_back(s.pdot), pddot.push_back(s.pddot);
  }
  kg::JsonWriter w(os, 0);
  w.begin_object();
  w.field("duration", warp.duration);
  w.field("source_duration", warp.source_duration);
  w.field("fps", fps);
  w.field("controls", warp.controls);
  w.field("t", t);
  w.field("p", p);
  w.field("pdot", pdot);
  w.field("pddot", pddot);
  w.end_object();
  os << '\n';
}

}  // namespace kg::retime
