#include "kg/retime/retime_clip.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kg/base/json.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/playback.hpp"

namespace kg::retime {

const char* to_string(TorqueTarget target) {
  switch (target) {
    case TorqueTarget::Original:
      return "match";
    case TorqueTarget::Zero:
      return "minimal";
    case TorqueTarget::Reference:
      return "reference";
  }
  return "?";
}

namespace {

std::string fixed(double x, int digits = 3) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << x;
  return out.str();
}

// The output time at which `warp` plays source time `p` (bisection: p(t) increases strictly).
double output_time_of(const TimeWarp& warp, double p) {
  double lo = 0, hi = warp.duration;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (warp.at(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// How far a flight frame's root residual may exceed its least, over the body's weight, and still
// count as at its closest point.
constexpr double kFlightTolerance = 0.1;

int nearest_frame(double p, double fps, int frames) {
  return std::clamp(static_cast<int>(std::lround(p * fps)), 0, frames - 1);
}

// A playback over `duration` output seconds that plays the clip's flights (intervals between
// two flight frames) at source speed and everything else at one constant speed: the start of
// the second solve (see retime_clip). Empty when the clip has no flight, or when its flights
// alone would take most of the duration.
std::vector<Pin> flight_at_source_speed(const Hulls& hulls, double fps, double duration) {
  const int frames = static_cast<int>(hulls.frames.size());
  auto flight = [&](int f) { return hulls.frames[static_cast<std::size_t>(f)].status == HullStatus::Flight; };
  int flying = 0;
  for (int f = 0; f + 1 < frames; ++f) flying += flight(f) && flight(f + 1);
  const double source_duration = (frames - 1) / fps, flight_time = flying / fps;
  if (flying == 0 || duration - flight_time < 0.1 * duration) return {};
  const double speed = (source_duration - flight_time) / (duration - flight_time);
  if (!(speed > 0) || !std::isfinite(speed)) return {};  // all flight: nothing else to play
  std::vector<Pin> playback{{0, 0}};
  for (int f = 0; f + 1 < frames; ++f)
    playback.push_back(
        {(f + 1) / fps, playback.back().output_time + (flight(f) && flight(f + 1) ? 1 : 1 / speed) / fps});
  playback.back() = {source_duration, duration};  // exactly, whatever the sum's rounding
  return playback;
}

}  // namespace

void ClipRetimeOptions::validate() const {
  using options::require;
  const char* o = "ClipRetimeOptions";
  require(options::non_negative(alpha), o, "alpha", alpha, ">= 0 and finite");
  require(options::non_negative(beta), o, "beta", beta, ">= 0 and finite");
  require(options::non_negative(flight_weight), o, "flight_weight", flight_weight, ">= 0 and finite");
  require(options::non_negative(inside_tolerance), o, "inside_tolerance", inside_tolerance,
          ">= 0 and finite (plane units)");
  time_optimal.validate();
  if (mode == RetimeMode::Optimise)
    solve.validate();
  else
    require(solve.samples_per_frame >= 1 && solve.samples_per_frame <= kMaxSamplesPerFrame, "RetimeOptions",
            "samples_per_frame", solve.samples_per_frame, "1 to " + std::to_string(kMaxSamplesPerFrame));
}

ClipRetime retime_clip(const Hulls& hulls, std::span<const FrameTorques> torques, double fps,
                       const ClipRetimeOptions& options, const motion::Skeleton& skeleton,
                       std::span<const Eigen::VectorXd> reference) {
  options.validate();
  const int frames = static_cast<int>(hulls.frames.size());
  if (static_cast<int>(torques.size()) != frames)
    throw std::invalid_argument("retime: " + std::to_string(torques.size()) + " frames of torques for " +
                                std::to_string(frames) + " hulls");
  if (frames < 2) throw std::invalid_argument("retime: the clip has fewer than 2 frames");
  const std::vector<Eigen::VectorXd> original = original_torques(hulls, torques);
  std::vector<Eigen::VectorXd> targets;
  switch (options.target) {
    case TorqueTarget::Original:
      targets = original;
      break;
    case TorqueTarget::Zero:
      for (const Eigen::VectorXd& t : original) targets.push_back(Eigen::VectorXd::Zero(t.size()));
      break;
    case TorqueTarget::Reference: {
      if (reference.empty())
        throw std::invalid_argument("retime: objective 'reference' needs the reference clip's torques");
      for (int f = 0; f < frames; ++f) {
        const std::size_t r = static_cast<std::size_t>(
            std::lround(static_cast<double>(f) / (frames - 1) * (static_cast<double>(reference.size()) - 1)));
        if (reference[r].size() != original[static_cast<std::size_t>(f)].size())
          throw std::invalid_argument("retime: the reference clip has another skeleton (" +
                                      std::to_string(reference[r].size()) + " channels, expected " +
                                      std::to_string(original[static_cast<std::size_t>(f)].size()) + ")");
        targets.push_back(reference[r]);
      }
      break;
    }
  }
  ClipRetime out;
  out.torque_scale = torque_scale(skeleton, original);
  const BakedObjective objective(hulls, torques, targets, skeleton, fps,
                                 {.alpha = options.alpha,
                                  .beta = options.beta,
                                  .torque_scale = out.torque_scale,
                                  .flight = options.flight_weight});

  std::vector<Polygon> polygons;
  auto time_optimal_playback = [&] {
    // Flight frames admit the timings whose root residual stays within a quarter of the weight
    // (captured flights scatter by that much from frame to frame).
    // Frames no timing makes physical (an empty polytope, a flight frame whose best residual is
    // larger: missed contacts, a T-pose frame) bound nothing: the plane's box.
    int unbounded = 0;
    if (polygons.empty()) {
      const double a = hulls.options.pddot_max, b = hulls.options.pdot2_max;
      for (int f = 0; f < frames; ++f) {
        polygons.push_back(objective.admissible_region(f, 0.25));
        if (polygons.back().empty()) {
          polygons.back() = {{-a, 0}, {a, 0}, {a, b}, {-a, b}};
          ++unbounded;
        }
      }
    }
    TimeOptimalResult r = time_optimal(polygons, fps, options.time_optimal);
    if (unbounded)
      r.message += " (" + std::to_string(unbounded) +
                   " frames no timing makes physical bound nothing: flight or contact the detection misread)";
    return r;
  };
  std::ostringstream message;
  if (options.mode == RetimeMode::TimeOptimal) {
    out.shortest = time_optimal_playback();
    if (!out.shortest->feasible) {
      out.feasible = false;
      out.message = "time-optimal retiming: " + out.shortest->message;
      return out;
    }
    out.warp = out.shortest->warp;
    message << "time-optimal playback: " << out.shortest->message << ". ";
  } else {
    out.solve = retime(objective, options.solve);
    // The objective has local minima (the fan's kinks, the flight's term against the ground
    // phases'), and which one a solve ends in depends on where it starts. A clip with flight is
    // solved twice, from constant speed and from its flights at source speed, and the lower
    // objective kept: bench_retime's jumps retimed to half their duration kept their flights near
    // source speed from either start in some runs and not in others.
    const std::vector<Pin> flight_start = options.solve.pins.empty() && options.solve.start.empty()
                                              ? flight_at_source_speed(hulls, fps, options.solve.duration)
                                              : std::vector<Pin>{};
    std::string starts;
    if (!flight_start.empty()) {
      RetimeOptions second = options.solve;
      second.start = flight_start;
      RetimeResult other = retime(objective, second);
      const auto value = [&](const RetimeResult& r) {
        return integrate(objective, r.warp, sample_grid(r.warp, fps, options.solve.samples_per_frame));
      };
      const bool flight_better = value(other) < value(out.solve);
      starts = std::string(", the better of two starts (constant speed; flights at source speed") +
               (flight_better ? ", kept" : "") + ")";
      other.iterations += out.solve.iterations;
      other.evaluations += out.solve.evaluations;
      other.seconds += out.solve.seconds;
      if (flight_better) {
        std::swap(out.solve, other);
      } else {
        out.solve.iterations = other.iterations;
        out.solve.evaluations = other.evaluations;
        out.solve.seconds = other.seconds;
      }
    }
    out.warp = out.solve.warp;
    message << (out.solve.converged ? "converged" : "did not converge") << " in " << out.solve.iterations
            << " iterations" << starts << " (" << out.solve.message << "). ";
  }

  // Parts of the objective and the share of output frames inside their hulls.
  for_each_sample(sample_grid(out.warp, fps, options.solve.samples_per_frame), out.warp.duration,
                  [&](double t, double w) {
                    const WarpSample s = out.warp.sample(t);
                    const BakedObjective::Parts parts =
                        objective.parts(nearest_frame(s.p, fps, frames), s.pddot, s.pdot * s.pdot);
                    out.feasibility += w * parts.feasibility;
                    out.torque += w * parts.torque;
                  });
  out.output_frames = output_frame_count(out.warp, fps);
  int feasible_frames = 0, inside = 0, point_frames = 0, at_point = 0;
  for (int k = 0; k < out.output_frames; ++k) {
    const WarpSample s = out.warp.sample(k / fps);
    const int f = nearest_frame(s.p, fps, frames);
    const FrameHull& hull = hulls.frames[static_cast<std::size_t>(f)];
    int hint = 0;
    const HullPoint c = closest_point(hull, Eigen::Vector2d(s.pddot, s.pdot * s.pdot), hint);
    const bool near = c.distance_squared <= options.inside_tolerance * options.inside_tolerance;
    if (hull.status == HullStatus::Feasible) {
      ++feasible_frames, inside += near;
    } else if (hull.status == HullStatus::Flight) {
      // A flight's point is as good as its rows: the residual may exceed its least by a tenth of
      // the weight.
      ++point_frames;
      at_point += objective.flight_excess(f, s.pddot, s.pdot * s.pdot) <= kFlightTolerance * kFlightTolerance;
    } else {
      ++point_frames, at_point += near;
    }
  }
  out.share_inside = feasible_frames ? static_cast<double>(inside) / feasible_frames : 1.0;
  out.share_at_point = point_frames ? static_cast<double>(at_point) / point_frames : 1.0;
  out.feasible = inside == feasible_frames;
  message << fixed(100 * out.share_inside, 1) << "% of " << feasible_frames
          << " output frames inside their hulls";
  if (point_frames)
    message << ", " << fixed(100 * out.share_at_point, 1) << "% of " << point_frames
            << " frames without a feasible polytope at their closest point (flight: root residual within "
            << fixed(100 * kFlightTolerance, 0) << "% of the weight of its least)";
  message << ".";
  if (!out.feasible && options.mode == RetimeMode::Optimise) {
    out.shortest = time_optimal_playback();
    if (out.shortest->feasible && options.solve.duration < out.shortest->duration)
      message << " The requested duration " << fixed(options.solve.duration)
              << " s is shorter than any feasible "
              << "playback: the shortest lasts " << fixed(out.shortest->duration) << " s.";
    else if (!out.shortest->feasible)
      message << " No timing keeps every frame inside its hull: " << out.shortest->message << ".";
  }
  out.message = message.str();
  return out;
}

void write_forces_json(std::ostream& os, const Hulls& hulls, std::span<const FrameTorques> torques,
                       const TimeWarp& warp, double fps) {
  kg::JsonWriter w(os, 0);
  w.begin_object();
  w.field("fps", fps);
  w.key("patches");
  w.begin_array();
  for (const std::string& name : hulls.patch_names) w.value(name);
  w.end_array();
  w.key("frames");
  w.begin_array();
  Eigen::VectorXd lambda;
  int hint = 0;
  for (std::size_t f = 0; f < hulls.frames.size(); ++f) {
    const FrameHull& hull = hulls.frames[f];
    const double t = output_time_of(warp, static_cast<double>(f) / fps);
    const WarpSample s = warp.sample(t);
    const Eigen::Vector2d x(s.pddot, s.pdot * s.pdot);
    lambda_at(hull, x, hint, lambda);
    int probe = hint;
    const HullPoint c = closest_point(hull, x, probe);
    w.begin_object();
    w.field("frame", static_cast<int>(f));
    w.field("status", to_string(hull.status));
    if (!hull.message.empty()) w.field("message", hull.message);
    std::vector<double> flat;
    for (const Eigen::Vector2d& v : hull.vertices) flat.push_back(v.x()), flat.push_back(v.y());
    w.field("hull", flat);
    w.field("centre", std::vector<double>{hull.centre.x(), hull.centre.y()});
    w.field("output_time", t);
    w.field("timing", std::vector<double>{x.x(), x.y()});
    w.field("distance", std::sqrt(c.distance_squared));
    w.key("contacts");
    w.begin_array();
    for (const PatchForce& p : patch_forces(hull, lambda)) {
      w.begin_object();
      w.field("patch", hulls.patch_names.at(static_cast<std::size_t>(p.patch)));
      w.field("force", std::vector<double>{p.force.x(), p.force.y(), p.force.z()});
      w.field("centre_of_pressure", std::vector<double>{p.centre_of_pressure.x(), p.centre_of_pressure.y(),
                                                        p.centre_of_pressure.z()});
      w.end_object();
    }
    w.end_array();
    Eigen::VectorXd tau = torques[f].at(x.y(), x.x(), hulls.gravity);
    if (hull.N.cols() > 0) tau.noalias() -= hull.N * lambda;
    w.field("torques", std::vector<double>(tau.data(), tau.data() + tau.size()));
    w.end_object();
  }
  w.end_array();
  w.end_object();
  os << '\n';
}

}  // namespace kg::retime
