#include "kg/retarget/at_rate.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include <boost/math/interpolators/cardinal_cubic_b_spline.hpp>

#include "kg/base/text.hpp"
#include "kg/retarget/initial_estimate.hpp"

namespace kg::retarget {

namespace {

// D(x) at fractional solve frames x, x in [0, frames - 1 + slack]: the C2 cubic through the
// samples (Boost.Math's cardinal cubic B-spline interpolant; end slopes estimated to O(h^4));
// linear with fewer than 5 samples, which a cubic cannot take without end slopes.
class SampledCurve {
 public:
  explicit SampledCurve(const Eigen::VectorXd& samples) : samples_(samples) {
    if (samples.size() >= 5)
      spline_.emplace(samples.data(), static_cast<std::size_t>(samples.size()), 0.0, 1.0);
  }

  double operator()(double x) const {
    const double last = static_cast<double>(samples_.size() - 1);
    if (last <= 0) return samples_[0];
    const double inside = std::clamp(x, 0.0, last);
    if (!spline_) {
      const int i = std::min(static_cast<int>(std::floor(inside)), static_cast<int>(last) - 1);
      const double u = x - i;  // may pass 1 past the end: the last segment's slope
      return samples_[i] + u * (samples_[i + 1] - samples_[i]);
    }
    const double value = (*spline_)(inside);
    return x > last ? value + (x - last) * spline_->prime(last) : value;
  }

 private:
  Eigen::VectorXd samples_;
  std::optional<boost::math::interpolators::cardinal_cubic_b_spline<double>> spline_;
};

void check_layouts(const motion::Motion& at_rate, const motion::Motion& solve_source,
                   const motion::Motion& initial, const motion::Motion& result) {
  at_rate.check();
  solve_source.check();
  initial.check();
  result.check();
  const int channels = solve_source.skeleton->channel_count();
  for (const auto& [what, m] :
       {std::pair{"the clip at the rate written", &at_rate}, std::pair{"the initial estimate", &initial},
        std::pair{"the result", &result}})
    if (m->skeleton->channel_count() != channels)
      throw std::invalid_argument(std::string("result_at_rate: ") + what + " has " +
                                  std::to_string(m->skeleton->channel_count()) +
                                  " channels, the solve's source " + std::to_string(channels));
  if (initial.frame_count() != solve_source.frame_count() ||
      result.frame_count() != solve_source.frame_count())
    throw std::invalid_argument("result_at_rate: the solve's source, initial estimate and result have " +
                                std::to_string(solve_source.frame_count()) + ", " +
                                std::to_string(initial.frame_count()) + " and " +
                                std::to_string(result.frame_count()) + " frames; they must agree");
  const double slack = 1.0 / std::min(at_rate.fps, solve_source.fps) + 1e-9;
  if (std::abs(at_rate.duration() - solve_source.duration()) > slack)
    throw std::invalid_argument("result_at_rate: the clip at the rate written lasts " +
                                text::significant(at_rate.duration()) + " s, the solve's source " +
                                text::significant(solve_source.duration()) +
                                " s: they are not the same clip at two rates");
}

}  // namespace

ResultAtRate result_at_rate(const motion::Motion& at_rate, const motion::Motion& solve_source,
                            const motion::Motion& initial, const motion::Motion& result,
                            const Target& target) {
  check_layouts(at_rate, solve_source, initial, result);
  if (at_rate.fps == solve_source.fps && at_rate.frame_count() == solve_source.frame_count())
    return {result, initial};

  const motion::Motion scaled_solve = scale_translation(solve_source, target);
  const motion::Motion scaled_out = scale_translation(at_rate, target);
  const motion::FrameMatrix displacement = result.values - scaled_solve.values;
  const motion::FrameMatrix shift = initial.values - scaled_solve.values;

  ResultAtRate out{result, initial};
  out.result.values = scaled_out.values;
  out.result.fps = at_rate.fps;
  out.initial.values = scaled_out.values;
  out.initial.fps = at_rate.fps;
  const double ratio = solve_source.fps / at_rate.fps;
  for (Eigen::Index c = 0; c < displacement.cols(); ++c) {
    const SampledCurve d(displacement.col(c));
    const bool shifted = shift.col(c).cwiseAbs().maxCoeff() > 0;
    const std::optional<SampledCurve> s = shifted ? std::optional<SampledCurve>(shift.col(c)) : std::nullopt;
    for (int g = 0; g < at_rate.frame_count(); ++g) {
      const double x = g * ratio;
      out.result.values(g, c) += d(x);
      if (s) out.initial.values(g, c) += (*s)(x);
    }
  }
  return out;
}

namespace {

int instant(const Sample& sample) {
  return *std::max_element(sample.frames.begin(), sample.frames.end());
}

template <class T>
std::vector<T> blended(const std::vector<T>& a, const std::vector<T>& b, double u) {
  if (a.size() != b.size() || u <= 0) return a;
  if (u >= 1) return b;
  std::vector<T> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) out[i] = (1 - u) * a[i] + u * b[i];
  return out;
}

// One run of samples (consecutive instants, sorted) at the new rate, appended to `out`.
void run_at_rate(std::span<const Sample* const> run, double ratio, int last_frame, std::vector<Sample>& out) {
  const auto to_frame = [&](double f) {
    return std::clamp(static_cast<int>(std::lround(f * ratio)), 0, last_frame);
  };
  if (run.size() == 1) {
    Sample s = *run[0];
    for (int& f : s.frames) f = to_frame(f);
    out.push_back(std::move(s));
    return;
  }
  const std::size_t appended = out.size();
  const int first_instant = instant(*run.front());
  const int start = *std::min_element(run.front()->frames.begin(), run.front()->frames.end());
  const int begin = std::clamp(static_cast<int>(std::ceil(start * ratio - 1e-9)), 0, last_frame);
  const int end =
      std::clamp(static_cast<int>(std::floor(instant(*run.back()) * ratio + 1e-9)), 0, last_frame);
  for (int g = begin; g <= end; ++g) {
    const double x = g / ratio;  // in the original frames
    const std::size_t k = static_cast<std::size_t>(
        std::clamp(static_cast<int>(std::floor(x)) - first_instant, 0, static_cast<int>(run.size()) - 1));
    const Sample& a = *run[k];
    const Sample& b = *run[std::min(k + 1, run.size() - 1)];
    const double u = x - instant(a);
    Sample s;
    const int at = instant(a);
    // An earlier frame stays at least one frame earlier: at a coarser rate a non-skid pair 1/120 s
    // apart reads consecutive frames, not one frame against itself.
    for (int f : a.frames) {
      const int back = f < at ? std::max(1, static_cast<int>(std::lround((at - f) * ratio))) : 0;
      s.frames.push_back(std::clamp(g - back, begin, g));
    }
    // A sample that reads one instant against an earlier one says nothing when both are g.
    if (s.frames.size() > 1 && std::all_of(s.frames.begin(), s.frames.end(), [g](int f) { return f == g; }))
      continue;
    s.params = blended(a.params, b.params, u);
    s.locals = blended(a.locals, b.locals, u);
    out.push_back(std::move(s));
  }
  // A run shorter than one frame of the new rate still holds at the frame nearest its middle,
  // when its samples read one instant each; a pair of instants has no two frames to compare.
  if (out.size() == appended && run.front()->frames.size() == 1) {
    Sample s = *run[run.size() / 2];
    for (int& f : s.frames) f = to_frame(f);
    out.push_back(std::move(s));
  }
}

}  // namespace

ConstraintSet constraints_at_rate(const ConstraintSet& set, double from_fps, double to_fps, int to_frames) {
  if (!(from_fps > 0) || !(to_fps > 0) || !std::isfinite(from_fps) || !std::isfinite(to_fps) || to_frames < 1)
    throw std::invalid_argument("constraints_at_rate: rates " + text::significant(from_fps) + " and " +
                                text::significant(to_fps) + " fps, " + std::to_string(to_frames) +
                                " frames (expected positive rates and at least one frame)");
  if (from_fps == to_fps) return set;
  ConstraintSet out;
  const double ratio = to_fps / from_fps;
  for (const Constraint& c : set.constraints) {
    Constraint moved = c;
    moved.samples.clear();
    std::vector<const Sample*> order;
    for (const Sample& s : c.samples)
      if (!s.frames.empty()) order.push_back(&s);
    std::stable_sort(order.begin(), order.end(),
                     [](const Sample* a, const Sample* b) { return instant(*a) < instant(*b); });
    std::size_t first = 0;
    for (std::size_t i = 1; i <= order.size(); ++i)
      if (i == order.size() || instant(*order[i]) != instant(*order[i - 1]) + 1) {
        run_at_rate(std::span<const Sample* const>(order.data() + first, i - first), ratio, to_frames - 1,
                    moved.samples);
        first = i;
      }
    if (!moved.samples.empty()) out.constraints.push_back(std::move(moved));
  }
  return out;
}

}  // namespace kg::retarget
