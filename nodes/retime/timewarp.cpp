#include "kg/retime/timewarp.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>
#include <Eigen/QR>

#include "kg/motion/bspline.hpp"

namespace kg::retime {

namespace {

std::string seconds(double s) {
  std::ostringstream out;
  out.precision(6);
  out << s << " s";
  return out.str();
}

void check_sizes(double source_duration, double duration, int segments) {
  if (!(std::isfinite(source_duration) && source_duration > 0))
    throw std::invalid_argument("time warp: source duration " + seconds(source_duration) + " (expected > 0)");
  if (!(std::isfinite(duration) && duration > 0))
    throw std::invalid_argument("time warp: duration " + seconds(duration) + " (expected > 0)");
  if (segments < 1)
    throw std::invalid_argument("time warp: " + std::to_string(segments) + " segments (expected >= 1)");
}

// The weights of p at output time t on a warp of the given layout.
WarpSample basis(double duration, int segments, double t) {
  const double h = duration / segments;
  const double u = std::clamp(t, 0.0, duration) / h;
  const int segment = std::clamp(static_cast<int>(std::floor(u)), 0, segments - 1);
  const motion::CubicWeights w = motion::cubic_bspline_weights(u - segment);
  WarpSample s;
  s.first = segment;
  for (int i = 0; i < 4; ++i) {
    s.weight[i] = w.value[i];
    s.weight_first[i] = w.first[i] / h;
    s.weight_second[i] = w.second[i] / (h * h);
  }
  return s;
}

}  // namespace

WarpSample TimeWarp::sample(double t) const {
  WarpSample s = basis(duration, segments(), t);
  for (int i = 0; i < 4; ++i) {
    const double c = controls[static_cast<std::size_t>(s.first + i)];
    s.p += s.weight[i] * c;
    s.pdot += s.weight_first[i] * c;
    s.pddot += s.weight_second[i] * c;
  }
  return s;
}

double TimeWarp::max_pdot(int segment) const {
  // ṗ(u) = ((d0 + d1) + 2 (d1 - d0) u + (d0 - 2 d1 + d2) u²) / 2h over u in [0, 1], with d the
  // segment's three control differences (the quadratic B-spline of the differences): its largest
  // value is at an end, or at the vertex when the parabola opens downwards.
  const std::size_t s = static_cast<std::size_t>(segment);
  const double d0 = controls[s + 1] - controls[s], d1 = controls[s + 2] - controls[s + 1],
               d2 = controls[s + 3] - controls[s + 2];
  const double a = d0 + d1, b = 2 * (d1 - d0), c = d0 - 2 * d1 + d2;
  double most = std::max(a, a + b + c);
  if (c < 0) {
    const double u = -b / (2 * c);
    if (u > 0 && u < 1) most = std::max(most, a + u * (b + u * c));
  }
  return most / (2 * knot_spacing());
}

bool TimeWarp::strictly_increasing(double margin) const {
  for (std::size_t j = 1; j < controls.size(); ++j)
    if (!(controls[j] - controls[j - 1] > margin)) return false;
  return true;
}

TimeWarp TimeWarp::uniform(double source_duration, double duration, int segments) {
  check_sizes(source_duration, duration, segments);
  TimeWarp warp{duration, source_duration, std::vector<double>(static_cast<std::size_t>(segments + 3))};
  const double speed = source_duration / duration, h = duration / segments;
  // A linear function's B-spline controls are its values at the controls' sites.
  for (int j = 0; j < segments + 3; ++j) warp.controls[static_cast<std::size_t>(j)] = speed * (j - 1) * h;
  return warp;
}

std::pair<int, int> held_segments(const Hold& hold, double duration, int segments) {
  const double h = duration / segments;
  // A hold ending on a knot does not touch the segment after it (up to rounding of the times).
  const double slack = 1e-9 * h;
  const int first =
      std::clamp(static_cast<int>(std::floor((hold.output_start + slack) / h)), 0, segments - 1);
  const int last = std::clamp(static_cast<int>(std::ceil((hold.output_start + hold.length - slack) / h)),
                              first + 1, segments);
  return {first, last};
}

namespace {

// Per control a hold fixes: its index and value (the line's value at the control's site).
std::vector<std::pair<int, double>> held_controls(double source_duration, double duration, int segments,
                                                  const std::vector<Hold>& holds) {
  const double h = duration / segments;
  std::vector<std::pair<int, double>> fixed;
  std::vector<int> owner(static_cast<std::size_t>(segments + 3), -1);
  std::vector<double> value(static_cast<std::size_t>(segments + 3), 0);
  for (std::size_t i = 0; i < holds.size(); ++i) {
    const Hold& hold = holds[i];
    const std::string name = "hold " + std::to_string(i) + " (source " + seconds(hold.source_start) +
                             " from output " + seconds(hold.output_start) + " for " + seconds(hold.length) +
                             " at speed " + std::to_string(hold.speed) + ")";
    if (!std::isfinite(hold.source_start) || !std::isfinite(hold.output_start) ||
        !std::isfinite(hold.length) || !std::isfinite(hold.speed))
      throw std::invalid_argument("time warp: " + name + ": expected finite numbers");
    if (!(hold.length > 0) || !(hold.speed > 0))
      throw std::invalid_argument("time warp: " + name + ": expected a positive length and speed");
    const auto [first, last] = held_segments(hold, duration, segments);
    auto line = [&](double t) { return hold.source_start + hold.speed * (t - hold.output_start); };
    if (hold.output_start < 0 || hold.output_start + hold.length > duration * (1 + 1e-12) ||
        line(first * h) < -1e-9 * source_duration || line(last * h) > source_duration * (1 + 1e-9))
      throw std::invalid_argument("time warp: " + name + ": its segments (output " + seconds(first * h) +
                                  " to " + seconds(last * h) + ", source " + seconds(line(first * h)) +
                                  " to " + seconds(line(last * h)) + ") leave the warp's " +
                                  seconds(duration) + " x the source's " + seconds(source_duration));
    for (int j = first; j <= last + 2; ++j) {
      const double v = line((j - 1) * h);
      const std::size_t k = static_cast<std::size_t>(j);
      if (owner[k] >= 0) {
        if (std::abs(value[k] - v) > 1e-12 * source_duration)
          throw std::invalid_argument("time warp: " + name + " and hold " + std::to_string(owner[k]) +
                                      " fix the same control to different values: they are closer than "
                                      "the spline's three segments of " +
                                      seconds(h) + " (use shorter segments)");
        continue;
      }
      owner[k] = static_cast<int>(i);
      value[k] = v;
      fixed.push_back({j, v});
    }
  }
  return fixed;
}

}  // namespace

WarpConstraints warp_constraints(double source_duration, double duration, int segments,
                                 const std::vector<Pin>& pins, const std::vector<Hold>& holds) {
  check_sizes(source_duration, duration, segments);
  for (std::size_t i = 0; i < pins.size(); ++i)  // before sorting: NaN does not order
    if (!std::isfinite(pins[i].source_time) || !std::isfinite(pins[i].output_time))
      throw std::invalid_argument("time warp: pin " + std::to_string(i) + " (source " +
                                  seconds(pins[i].source_time) + " at output " +
                                  seconds(pins[i].output_time) + "): expected finite times");
  std::vector<Pin> sorted = pins;
  std::sort(sorted.begin(), sorted.end(),
            [](const Pin& a, const Pin& b) { return a.output_time < b.output_time; });
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const Pin& pin = sorted[i];
    const std::string name =
        "pin (source " + seconds(pin.source_time) + " at output " + seconds(pin.output_time) + ")";
    if (!(pin.output_time > 0 && pin.output_time < duration))
      throw std::invalid_argument("time warp: " + name + ": output time outside (0, " + seconds(duration) +
                                  ")");
    if (!(pin.source_time > 0 && pin.source_time < source_duration))
      throw std::invalid_argument("time warp: " + name + ": source time outside (0, " +
                                  seconds(source_duration) + ")");
    if (i > 0) {
      const Pin& before = sorted[i - 1];
      if (pin.output_time == before.output_time)
        throw std::invalid_argument("time warp: two pins at output " + seconds(pin.output_time));
      if (!(pin.source_time > before.source_time))
        throw std::invalid_argument("time warp: contradictory pins: source " + seconds(before.source_time) +
                                    " at output " + seconds(before.output_time) + " but source " +
                                    seconds(pin.source_time) + " later, at output " +
                                    seconds(pin.output_time) + " (playback cannot run backwards)");
    }
  }
  const auto fixed = held_controls(source_duration, duration, segments, holds);
  const int controls = segments + 3;
  const int rows = 2 + static_cast<int>(sorted.size() + fixed.size());
  WarpConstraints c{Eigen::MatrixXd::Zero(rows, controls), Eigen::VectorXd::Zero(rows)};
  auto add_row = [&](int row, double t, double value) {
    const WarpSample s = basis(duration, segments, t);
    for (int i = 0; i < 4; ++i) c.A(row, s.first + i) = s.weight[i];
    c.b[row] = value;
  };
  add_row(0, 0.0, 0.0);
  add_row(1, duration, source_duration);
  for (std::size_t i = 0; i < sorted.size(); ++i)
    add_row(2 + static_cast<int>(i), sorted[i].output_time, sorted[i].source_time);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    const int row = 2 + static_cast<int>(sorted.size() + i);
    c.A(row, fixed[i].first) = 1;
    c.b[row] = fixed[i].second;
  }
  return c;
}

TimeWarp initial_warp(double source_duration, double duration, int segments, const std::vector<Pin>& pins,
                      const std::vector<Pin>& playback, const std::vector<Hold>& holds) {
  const WarpConstraints constraints = warp_constraints(source_duration, duration, segments, pins, holds);
  // Knots of the piecewise-linear playback: the given playback, or the ends and the pins in
  // output order.
  std::vector<Pin> knots = playback;
  for (std::size_t k = 1; k < knots.size(); ++k)
    if (!(knots[k].output_time > knots[k - 1].output_time) ||
        !(knots[k].source_time >= knots[k - 1].source_time))
      throw std::invalid_argument("time warp: the starting playback's sample " + std::to_string(k) +
                                  " does not follow sample " + std::to_string(k - 1) +
                                  " (output times must increase, source times not decrease)");
  if (knots.size() == 1) throw std::invalid_argument("time warp: a starting playback of one sample");
  if (knots.empty()) {
    knots = pins;
    knots.push_back({0, 0});
    knots.push_back({source_duration, duration});
    std::sort(knots.begin(), knots.end(),
              [](const Pin& a, const Pin& b) { return a.output_time < b.output_time; });
  }
  auto linear = [&](double t) {
    const auto after = std::lower_bound(knots.begin() + 1, knots.end() - 1, t,
                                        [](const Pin& k, double time) { return k.output_time < time; });
    const Pin &a = *(after - 1), &b = *after;
    return a.source_time +
           (t - a.output_time) * (b.source_time - a.source_time) / (b.output_time - a.output_time);
  };
  TimeWarp warp = TimeWarp::uniform(source_duration, duration, segments);
  const double h = warp.knot_spacing();
  Eigen::VectorXd c(segments + 3);
  for (int j = 0; j < segments + 3; ++j) c[j] = linear((j - 1) * h);
  // The nearest controls meeting the constraints exactly (least-norm correction).
  const Eigen::MatrixXd& A = constraints.A;
  const Eigen::VectorXd correction =
      A.transpose() * (A * A.transpose()).fullPivLu().solve(constraints.b - A * c);
  c += correction;
  warp.controls.assign(c.data(), c.data() + c.size());
  if (!warp.strictly_increasing() || (A * c - constraints.b).cwiseAbs().maxCoeff() > 1e-9 * source_duration) {
    double closest = duration;
    for (std::size_t i = 1; i < knots.size(); ++i)
      closest = std::min(closest, knots[i].output_time - knots[i - 1].output_time);
    if (!holds.empty())
      throw std::invalid_argument("time warp: " + std::to_string(segments) + " segments of " + seconds(h) +
                                  " cannot pass the pins and holds increasingly (a hold too near an end, a "
                                  "pin or another hold): use shorter segments");
    throw std::invalid_argument("time warp: " + std::to_string(segments) + " segments of " + seconds(h) +
                                " cannot pass the pins increasingly; the closest pins (or ends) are " +
                                seconds(closest) + " apart: use shorter segments");
  }
  return warp;
}

TimeWarp fit_warp(const std::vector<double>& output_times, const std::vector<double>& source_times,
                  int segments) {
  if (output_times.size() != source_times.size() || output_times.size() < 2)
    throw std::invalid_argument("time warp fit: " + std::to_string(output_times.size()) +
                                " output times and " + std::to_string(source_times.size()) +
                                " source times (expected equal, >= 2)");
  if (output_times.front() != 0 || source_times.front() != 0)
    throw std::invalid_argument("time warp fit: the samples must start at output 0, source 0");
  for (std::size_t k = 1; k < output_times.size(); ++k)
    if (!(output_times[k] > output_times[k - 1]) || !(source_times[k] >= source_times[k - 1]))
      throw std::invalid_argument("time warp fit: sample " + std::to_string(k) + " does not follow sample " +
                                  std::to_string(k - 1) +
                                  " (output times must increase, source times not decrease)");
  const double duration = output_times.back(), source_duration = source_times.back();
  check_sizes(source_duration, duration, segments);
  // The playback through the samples, linear between them and extended linearly past the ends.
  auto linear = [&](double t) {
    const auto it = std::upper_bound(output_times.begin(), output_times.end(), t);
    const std::size_t k = std::clamp<std::size_t>(static_cast<std::size_t>(it - output_times.begin()), 1,
                                                  output_times.size() - 1);
    const double t0 = output_times[k - 1], t1 = output_times[k];
    return source_times[k - 1] + (t - t0) * (source_times[k] - source_times[k - 1]) / (t1 - t0);
  };
  // Controls at their sites sample that monotone curve, so the spline is monotone too (a B-spline
  // never varies more than its controls); the two ends are then corrected onto their rows.
  const double h = duration / segments;
  Eigen::VectorXd c(segments + 3);
  for (int j = 0; j < segments + 3; ++j) c[j] = linear((j - 1) * h);
  const WarpConstraints ends = warp_constraints(source_duration, duration, segments, {});
  c += ends.A.transpose() * (ends.A * ends.A.transpose()).fullPivLu().solve(ends.b - ends.A * c);
  return TimeWarp{duration, source_duration, std::vector<double>(c.data(), c.data() + c.size())};
}

}  // namespace kg::retime
