#include "kg/retime/retime_clip.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
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

const char* to_string(FlightTiming timing) {
  return timing == FlightTiming::Hold ? "hold" : "free";
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

// Runs of two or more consecutive flight frames, as [first, last] source frames.
std::vector<std::pair<int, int>> flight_runs(const Hulls& hulls) {
  std::vector<std::pair<int, int>> runs;
  const int frames = static_cast<int>(hulls.frames.size());
  for (int f = 0; f < frames;) {
    if (hulls.frames[static_cast<std::size_t>(f)].status != HullStatus::Flight) {
      ++f;
      continue;
    }
    int last = f;
    while (last + 1 < frames && hulls.frames[static_cast<std::size_t>(last + 1)].status == HullStatus::Flight)
      ++last;
    if (last > f) runs.push_back({f, last});
    f = last + 1;
  }
  return runs;
}

// The playback the held solve starts from: constant speed between the ends, the pins and each
// hold's fixed controls (which it plays on the hold's line, so they need no correction).
std::vector<Pin> held_start(const TimeWarp& layout, const std::vector<Hold>& holds,
                            const std::vector<Pin>& pins) {
  std::vector<Pin> knots = pins;
  const double h = layout.knot_spacing();
  for (const Hold& hold : holds) {
    const auto [first, last] = held_segments(hold, layout.duration, layout.segments());
    for (const double t : {(first - 1) * h, first * h, last * h, (last + 1) * h})
      knots.push_back({hold.source_start + hold.speed * (t - hold.output_start), t});
  }
  std::sort(knots.begin(), knots.end(),
            [](const Pin& a, const Pin& b) { return a.output_time < b.output_time; });
  std::vector<Pin> playback{{0, 0}};
  for (const Pin& k : knots)
    if (k.output_time > playback.back().output_time && k.output_time < layout.duration &&
        k.source_time > playback.back().source_time && k.source_time < layout.source_duration)
      playback.push_back(k);
  playback.push_back({layout.source_duration, layout.duration});
  return playback;
}

// Where a held flight starts in the output, given its source frames and held length (output s).
using FlightPlacement = std::function<double(int first, int last, double length)>;

// FlightTiming::Hold: each flight held at the speed the hulls' gravity gives, placed by `place`
// over `duration` output seconds. Empty, with `note` saying why, when no flight can be held so.
std::vector<Hold> flight_holds(const Hulls& hulls, double fps, double duration, const FlightPlacement& place,
                               double& speed, std::string& note) {
  const auto runs = flight_runs(hulls);
  if (runs.empty()) {
    note = "no flight to hold (no two consecutive frames without contact)";
    return {};
  }
  const Eigen::Vector3d g = hulls.gravity;
  if (!(g.y() < 0) || std::hypot(g.x(), g.z()) > 1e-9 * g.norm()) {
    note = "flights not held: gravity (" + fixed(g.x()) + ", " + fixed(g.y()) + ", " + fixed(g.z()) +
           ") m/s^2 is not straight down, so no constant playback is ballistic (they are weighed instead)";
    return {};
  }
  speed = std::sqrt(g.norm() / motion::kEarthGravity);
  double total = 0;
  for (const auto& [first, last] : runs) total += (last - first) / fps / speed;
  if (total >= duration) {
    note = "flights not held: at the speed gravity gives (" + fixed(speed) + "x) they alone last " +
           fixed(total) + " s, not less than the " + fixed(duration) + " s requested";
    return {};
  }
  std::vector<Hold> holds;
  double end = 0;
  for (const auto& [first, last] : runs) {
    const double source_start = first / fps, length = (last - first) / fps / speed;
    // A flight the clip starts or ends in starts or ends the output: the ends are kept.
    const int final_frame = static_cast<int>(hulls.frames.size()) - 1;
    const double placed = first == 0            ? 0.0
                          : last == final_frame ? duration - length
                                                : place(first, last, length);
    const double start = std::clamp(std::max(placed, end), 0.0, duration - length);
    holds.push_back({source_start, start, length, speed});
    end = start + length;
  }
  return holds;
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

namespace {

// The holds the warp of `options` (its knot spacing, duration, pins) can meet together: the
// longest flights first, each kept when the warp can still start meeting it and those before.
std::vector<Hold> compatible_holds(std::vector<Hold> holds, double source_duration,
                                   const RetimeOptions& options, std::string& dropped) {
  std::stable_sort(holds.begin(), holds.end(),
                   [](const Hold& a, const Hold& b) { return a.length > b.length; });
  const int segments = warp_segments(options);
  const TimeWarp layout = TimeWarp::uniform(source_duration, options.duration, segments);
  std::vector<Hold> kept;
  dropped.clear();
  for (const Hold& hold : holds) {
    std::vector<Hold> trial = kept;
    trial.push_back(hold);
    std::sort(trial.begin(), trial.end(),
              [](const Hold& a, const Hold& b) { return a.output_start < b.output_start; });
    try {
      initial_warp(source_duration, options.duration, segments, options.pins,
                   held_start(layout, trial, options.pins), trial);
      kept = std::move(trial);
    } catch (const std::invalid_argument&) {
      dropped += (dropped.empty() ? "" : ", ") + fixed(hold.source_start) + " s";
    }
  }
  return kept;
}

// Solves again with the flights held (flight_holds), placed where out.solve's free solution plays
// them, and keeps the held solution in out.solve. Flights the spline cannot hold together (near
// an end, a pin or each other) are held on a knot spacing halved, twice at most, or left free.
void hold_flights(const PathObjective& objective, const Hulls& hulls, double fps, const RetimeOptions& solve,
                  ClipRetime& out) {
  // Placed where the free solve plays each flight's middle (its ground phases took the time their
  // hulls needed), else, when that holds fewer flights, between ground phases played at one speed.
  const TimeWarp& free = out.solve.warp;
  const FlightPlacement where_free = [&](int first, int last, double length) {
    return output_time_of(free, (first + last) / (2 * fps)) - length / 2;
  };
  const auto runs = flight_runs(hulls);
  out.flights = static_cast<int>(runs.size());
  double placing_duration = solve.duration;  // the output duration even_ground places flights in
  const FlightPlacement even_ground = [&](int first, int, double) {
    double flown = 0, flown_output = 0, flight_total = 0;  // source seconds in flight before `first`
    const double k = std::sqrt(hulls.gravity.norm() / motion::kEarthGravity);
    for (const auto& [a, b] : runs) flight_total += (b - a) / fps;
    for (const auto& [a, b] : runs)
      if (a < first) flown += (b - a) / fps, flown_output += (b - a) / fps / k;
    const double ground_speed =
        (objective.source_duration() - flight_total) / (placing_duration - flight_total / k);
    if (!(ground_speed > 0) || !std::isfinite(ground_speed)) return where_free(first, first, 0);
    return (first / fps - flown) / ground_speed + flown_output;
  };
  double speed = 0;
  RetimeOptions held = solve;
  std::string dropped;
  const char* placement = "";
  for (const FlightPlacement* place : {&where_free, &even_ground}) {
    const std::vector<Hold> all = flight_holds(hulls, fps, solve.duration, *place, speed, out.flight_note);
    if (all.empty()) return;
    RetimeOptions trial = solve;
    std::string trial_dropped;
    for (int attempt = 0; attempt < 3; ++attempt, trial.knot_spacing /= 2) {
      trial.holds = compatible_holds(all, objective.source_duration(), trial, trial_dropped);
      if (trial.holds.size() > held.holds.size()) {
        held = trial;
        dropped = trial_dropped;
        placement =
            place == &where_free ? "where the free solve played them" : "between evenly played ground phases";
      }
      if (held.holds.size() == all.size()) break;
    }
    if (held.holds.size() == all.size()) break;
  }
  if (held.holds.empty()) {
    out.flight_note = "flights not held: the spline of " + fixed(solve.knot_spacing) +
                      " s knots cannot hold them, even halved twice (they are weighed instead)";
    return;
  }
  if (static_cast<int>(held.holds.size()) < out.flights && solve.pins.empty()) {
    // The shortest duration whose spline holds every flight, between ground phases played evenly.
    const auto holds_all = [&](double duration) {
      placing_duration = duration;
      double unused_speed = 0;
      std::string unused_note, unused_dropped;
      const std::vector<Hold> all =
          flight_holds(hulls, fps, duration, even_ground, unused_speed, unused_note);
      if (static_cast<int>(all.size()) < out.flights) return false;
      RetimeOptions trial = solve;
      trial.duration = duration;
      for (int attempt = 0; attempt < 3; ++attempt, trial.knot_spacing /= 2)
        if (compatible_holds(all, objective.source_duration(), trial, unused_dropped).size() == all.size())
          return true;
      return false;
    };
    double low = solve.duration, high = objective.source_duration() / speed;
    if (high > low && holds_all(high)) {
      while (high - low > 1e-3) {
        const double middle = (low + high) / 2;
        (holds_all(middle) ? high : low) = middle;
      }
      out.duration_holding_flights = high;
    }
    placing_duration = solve.duration;
  }
  held.start = held_start(TimeWarp::uniform(objective.source_duration(), held.duration, warp_segments(held)),
                          held.holds, held.pins);
  RetimeResult result = retime(objective, held);
  result.iterations += out.solve.iterations;
  result.evaluations += out.solve.evaluations;
  result.seconds += out.solve.seconds;
  out.solve = std::move(result);
  out.flights_held = static_cast<int>(held.holds.size());
  out.held_speed = speed;
  double held_time = 0;
  for (const Hold& h : held.holds) held_time += h.length;
  out.flight_note = std::to_string(held.holds.size()) + (held.holds.size() == 1 ? " flight" : " flights") +
                    " held (" + fixed(held_time) + " s of output at " + fixed(speed) +
                    "x source speed, p'' = 0: ballistic under the hulls' gravity, placed " + placement + ")";
  if (held.knot_spacing != solve.knot_spacing)
    out.flight_note += ", knot spacing " + fixed(held.knot_spacing) + " s";
  if (!dropped.empty())
    out.flight_note += "; the flights from source " + dropped +
                       " are not held (with the longer flights, the ends and the pins held too, the spline "
                       "cannot play them increasingly at these knots)";
}

}  // namespace

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
    if (options.flights == FlightTiming::Hold) hold_flights(objective, hulls, fps, options.solve, out);
    out.warp = out.solve.warp;
    message << (out.solve.converged ? "converged" : "did not converge") << " in " << out.solve.iterations
            << " iterations" << starts << " (" << out.solve.message << "). ";
    if (!out.flight_note.empty()) message << out.flight_note << ". ";
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
  // What could not be met, in one plain sentence ahead of the details.
  std::string headline;
  if (!out.feasible && options.mode == RetimeMode::Optimise) {
    out.shortest = time_optimal_playback();
    const std::string outside =
        fixed(100 * (1 - out.share_inside), 0) + "% of the output frames with contact";
    if (out.shortest->feasible && options.solve.duration < out.shortest->duration)
      headline = "Not physical: the requested " + fixed(options.solve.duration) +
                 " s is shorter than any feasible playback: the shortest lasts " +
                 fixed(out.shortest->duration) + " s, so " + outside +
                 " play outside what their contacts allow (the closest playback is written). ";
    else if (!out.shortest->feasible)
      headline = "Not physical: no playback keeps every frame of this clip inside its hull (" +
                 out.shortest->message + "), so " + outside +
                 " play outside what their contacts allow (the closest playback is written). ";
    else
      headline = "Not physical: the playback of " + fixed(options.solve.duration) + " s found leaves " +
                 outside +
                 " outside what their contacts allow (it is written; the shortest physical playback lasts " +
                 fixed(out.shortest->duration) + " s). ";
  }
  if (out.flights_held < out.flights && out.flights_held > 0) {
    std::string flights_headline = "Not ballistic: " + std::to_string(out.flights - out.flights_held) +
                                   " of " + std::to_string(out.flights) +
                                   " flights play off their timing under gravity in " +
                                   fixed(options.solve.duration) +
                                   " s (the spline cannot hold every flight with "
                                   "the ground phases between them)";
    flights_headline += out.duration_holding_flights ? "; the shortest duration that holds them all is " +
                                                           fixed(*out.duration_holding_flights) + " s. "
                                                     : ". ";
    headline = flights_headline + headline;
  }
  out.message = headline + message.str();
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
