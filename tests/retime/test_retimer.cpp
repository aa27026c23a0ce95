#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "kg/retime/retimer.hpp"

using namespace kg::retime;

namespace {

// A stand-in for eq. 14 whose optimum is known: playback speed should be `flight_speed` while
// the source is between 1 and 2 s (weight `stiff`), 1 elsewhere (weight 1), with a smooth
// p-dependence so the d_p path is exercised.
class SpeedObjective final : public PathObjective {
 public:
  explicit SpeedObjective(double stiff) : stiff_(stiff) {}
  SampleCost evaluate(double p, double pddot, double pdot2, int&) const override {
    // weight(p) rises smoothly from 1 to `stiff` over [0.8, 1.0] and falls over [2.0, 2.2].
    auto smooth = [](double x) { return x <= 0 ? 0.0 : x >= 1 ? 1.0 : x * x * (3 - 2 * x); };
    auto dsmooth = [](double x) { return x <= 0 || x >= 1 ? 0.0 : 6 * x * (1 - x); };
    const double rise = smooth((p - 0.8) / 0.2), fall = smooth((p - 2.0) / 0.2);
    const double weight = 1 + (stiff_ - 1) * (rise - fall);
    const double dweight = (stiff_ - 1) * (dsmooth((p - 0.8) / 0.2) - dsmooth((p - 2.0) / 0.2)) / 0.2;
    const double e = pdot2 - 1;
    return {.value = weight * e * e + 1e-3 * pddot * pddot,
            .d_p = dweight * e * e,
            .d_pddot = 2e-3 * pddot,
            .d_pdot2 = 2 * weight * e};
  }
  double source_duration() const override { return 3.0; }
  double source_fps() const override { return 30.0; }

 private:
  double stiff_;
};

// `inner` times `scale`: the same minimum in other units.
class ScaledObjective final : public PathObjective {
 public:
  ScaledObjective(const PathObjective& inner, double scale) : inner_(inner), scale_(scale) {}
  SampleCost evaluate(double p, double pddot, double pdot2, int& hint) const override {
    const SampleCost c = inner_.evaluate(p, pddot, pdot2, hint);
    return {scale_ * c.value, scale_ * c.d_p, scale_ * c.d_pddot, scale_ * c.d_pdot2};
  }
  double source_duration() const override { return inner_.source_duration(); }
  double source_fps() const override { return inner_.source_fps(); }

 private:
  const PathObjective& inner_;
  double scale_;
};

}  // namespace

// A warp of `segments` segments over 2 s whose playback speeds up sevenfold: controls at their
// sites on p(t) = 0.5 t + 0.25 t³ (ṗ from 0.5 to 3.5; 3 s of source).
TimeWarp uneven_warp(int segments) {
  TimeWarp warp = TimeWarp::uniform(3.0, 2.0, segments);
  const double h = warp.knot_spacing();
  for (int j = 0; j < segments + 3; ++j) {
    const double t = (j - 1) * h;
    warp.controls[static_cast<std::size_t>(j)] = 0.5 * t + 0.25 * t * t * t;
  }
  return warp;
}

// integrate's gradient against central differences of integrate on the same grid.
void check_gradient(const PathObjective& objective, const TimeWarp& warp, const SampleGrid& grid) {
  std::vector<double> gradient(warp.controls.size());
  integrate(objective, warp, grid, gradient.data());
  for (std::size_t j = 0; j < warp.controls.size(); ++j) {
    const double h = 1e-6;
    TimeWarp plus = warp, minus = warp;
    plus.controls[j] += h;
    minus.controls[j] -= h;
    const double fd = (integrate(objective, plus, grid) - integrate(objective, minus, grid)) / (2 * h);
    INFO("control " << j);
    CHECK(gradient[j] == Approx(fd).epsilon(1e-5).margin(1e-6));
  }
}

TEST_CASE("integrate's gradient with respect to the controls matches finite differences on uneven grids") {
  const SpeedObjective objective(50);
  const TimeWarp warp = uneven_warp(16);
  SECTION("the retimer's grid, denser where the warp plays faster") {
    const SampleGrid grid = sample_grid(warp, 30, 4);
    CHECK(*std::max_element(grid.steps.begin(), grid.steps.end()) >
          2 * *std::min_element(grid.steps.begin(), grid.steps.end()));
    check_gradient(objective, warp, grid);
  }
  SECTION("any counts, one step per segment included") {
    SampleGrid grid;
    for (int s = 0; s < warp.segments(); ++s) grid.steps.push_back(1 + (7 * s) % 5);
    check_gradient(objective, warp, grid);
  }
}

TEST_CASE("sample_grid gives each segment the fewest steps that keep every step within a quarter frame") {
  const double fps = 30;
  const int per_frame = 4;
  const TimeWarp warp = uneven_warp(20);
  const SampleGrid grid = sample_grid(warp, fps, per_frame);
  REQUIRE(static_cast<int>(grid.steps.size()) == warp.segments());
  const double h = warp.knot_spacing(), quarter = 1 / (fps * per_frame);
  for (int s = 0; s < warp.segments(); ++s) {
    const int n = grid.steps[static_cast<std::size_t>(s)];
    INFO("segment " << s << ", " << n << " steps");
    // Playback sampled densely across the segment: a lower bound of its fastest.
    double fastest = 0;
    for (int k = 0; k <= 1000; ++k) fastest = std::max(fastest, warp.sample((s + k / 1000.0) * h).pdot);
    CHECK(warp.max_pdot(s) >= fastest * (1 - 1e-12));
    // No step covers more than a quarter frame of source...
    for (int k = 0; k < n; ++k) {
      const double t0 = s * h + k * h / n, t1 = s * h + (k + 1) * h / n;
      CHECK(warp.at(t1) - warp.at(t0) <= quarter * (1 + 1e-9));
      CHECK((t1 - t0) * warp.max_pdot(s) <= quarter * (1 + 1e-9));
    }
    // ... and one step fewer would let a step at the fastest playback cover more.
    if (n > 1) CHECK(h / (n - 1) * fastest > quarter);
  }
  // One grid at the fastest playback anywhere would take far more samples.
  double fastest = 0;
  for (int s = 0; s < warp.segments(); ++s) fastest = std::max(fastest, warp.max_pdot(s));
  CHECK(grid.samples() < 0.6 * (warp.duration * fastest * fps * per_frame));
  // A uniform warp needs exactly its quarter frames: 3 s of 30 fps source in 4 * 90 steps.
  CHECK(sample_grid(TimeWarp::uniform(3.0, 2.0, 20), fps, per_frame).samples() == 4 * 90 + 1);
  // At one sample per frame a segment plays 4.5 frames: 5 steps each, whole steps per segment.
  CHECK(sample_grid(TimeWarp::uniform(3.0, 2.0, 20), fps, 1).samples() == 20 * 5 + 1);
}

TEST_CASE("the trapezoid rule on a grid: weights summing to the duration, second-order error") {
  const TimeWarp warp = uneven_warp(12);
  SampleGrid grid;
  for (int s = 0; s < warp.segments(); ++s) grid.steps.push_back(1 + s % 4);
  double last = -1, weights = 0;
  int count = 0;
  for_each_sample(grid, warp.duration, [&](double t, double w) {
    CHECK(t > last);
    CHECK(w > 0);
    last = t;
    weights += w;
    ++count;
  });
  CHECK(last == warp.duration);
  CHECK(count == grid.samples());
  CHECK(weights == Approx(warp.duration).epsilon(1e-14));
  // ∫ ṗ dt = p(duration) − p(0), up to the rule's error on a quadratic ṗ, which halves and
  // halves again as the steps double.
  class Playback final : public PathObjective {
   public:
    SampleCost evaluate(double, double, double pdot2, int&) const override {
      return {.value = std::sqrt(pdot2)};
    }
    double source_duration() const override { return 3.0; }
    double source_fps() const override { return 30.0; }
  } playback;
  SampleGrid finer = grid;
  for (int& n : finer.steps) n *= 2;
  const double exact = warp.at(warp.duration) - warp.at(0);
  const double coarse_error = std::abs(integrate(playback, warp, grid) - exact);
  const double fine_error = std::abs(integrate(playback, warp, finer) - exact);
  CHECK(coarse_error < 1e-2);
  CHECK(fine_error == Approx(coarse_error / 4).epsilon(0.05));
}

TEST_CASE("integrate and sample_grid refuse grids and rates that do not fit") {
  const SpeedObjective objective(2);
  const TimeWarp warp = uneven_warp(8);
  CHECK_THROWS_WITH(
      integrate(objective, warp, SampleGrid{{1, 2, 3}}),
      "integrate: a grid of 3 segment counts for a warp of 8 segments (expected one count >= 1 per "
      "segment)");
  CHECK_THROWS_AS(integrate(objective, warp, SampleGrid{{1, 1, 1, 0, 1, 1, 1, 1}}), std::invalid_argument);
  CHECK_THROWS_WITH(sample_grid(warp, 0, 4), Catch::Matchers::StartsWith("sample grid: source fps 0"));
  CHECK_THROWS_WITH(sample_grid(warp, 30, 0), "sample grid: samples_per_frame 0 (expected 1 to 1000)");
}

TEST_CASE("the retimer keeps the stiff part at its speed and takes the time from the rest") {
  const SpeedObjective objective(200);
  const RetimeResult r = retime(objective, {.duration = 2.0});
  INFO(r.message);
  CHECK(r.converged);
  CHECK(r.warp.at(0) == Approx(0).margin(1e-9));
  CHECK(r.warp.at(2.0) == Approx(3.0));
  CHECK(r.warp.strictly_increasing());
  // The stiff second plays at about 1x, so the other two seconds of source fit into one of output.
  double t_in = 0, t_out = 0;
  for (double t = 0; t <= 2.0; t += 1e-4) {
    if (t_in == 0 && r.warp.at(t) >= 1.2) t_in = t;
    if (t_out == 0 && r.warp.at(t) >= 1.8) t_out = t;
  }
  CHECK(t_out - t_in == Approx(0.6).epsilon(0.05));
  CHECK(r.warp.sample(0.5 * (t_in + t_out)).pdot == Approx(1.0).epsilon(0.05));
}

TEST_CASE("the retimer's final grid has every segment's quarter frames at the solution's playback") {
  const SpeedObjective objective(200);
  const RetimeResult r = retime(objective, {.duration = 2.0, .knot_spacing = 0.1});
  INFO(r.message);
  CHECK(r.converged);
  REQUIRE(static_cast<int>(r.grid.steps.size()) == r.warp.segments());
  CHECK(r.samples == r.grid.samples());
  const SampleGrid needed = sample_grid(r.warp, objective.source_fps(), 4);
  for (std::size_t s = 0; s < needed.steps.size(); ++s) CHECK(needed.steps[s] <= r.grid.steps[s]);
  // The stiff second plays at 1x, the rest near 2x: its segments need about half the steps.
  CHECK(*std::max_element(r.grid.steps.begin(), r.grid.steps.end()) >=
        1.7 * *std::min_element(r.grid.steps.begin(), r.grid.steps.end()));
  CHECK(r.objective == Approx(integrate(objective, r.warp, r.grid)));
  // It started uniform at 1.5x: the segments sped up to about 2x were refined, and the message
  // says so.
  CHECK(r.samples > sample_grid(TimeWarp::uniform(3.0, 2.0, 20), 30, 4).samples());
  CHECK_THAT(r.message, Catch::Matchers::Contains(" segments from 361 to "));
}

TEST_CASE("pins hold exactly after the solve") {
  const SpeedObjective objective(20);
  const RetimeResult r =
      retime(objective, {.duration = 2.5, .pins = {{.source_time = 1.5, .output_time = 1.0}}});
  CHECK(r.converged);
  CHECK(r.warp.at(1.0) == Approx(1.5).epsilon(1e-9));
  CHECK(r.warp.at(2.5) == Approx(3.0).epsilon(1e-9));
}

TEST_CASE("the gradient tolerance is relative: objectives in small and large units both solve to it") {
  // Ceres' gradient test is absolute; were the option passed through, the objective a million
  // times smaller would start below it and stop where it started, the one a thousand times
  // larger would never reach it.
  const SpeedObjective unit(200);
  const RetimeOptions options{.duration = 2.0, .function_tolerance = 0, .gradient_tolerance = 1e-2};
  const ScaledObjective large_units(unit, 1e3), small_units(unit, 1e-6);
  const RetimeResult large = retime(large_units, options);
  const RetimeResult small = retime(small_units, options);
  INFO(large.message << "\n" << small.message);
  CHECK(large.converged);
  CHECK(small.converged);
  CHECK_THAT(large.message, Catch::Matchers::StartsWith("Gradient tolerance reached"));
  CHECK_THAT(small.message, Catch::Matchers::StartsWith("Gradient tolerance reached"));
  const TimeWarp uniform = TimeWarp::uniform(3.0, 2.0, 20);
  const double start = integrate(unit, uniform, sample_grid(uniform, 30, 4));
  const double solved = large.objective / 1e3;
  CHECK(solved < 0.5 * start);
  CHECK(small.objective / 1e-6 == Approx(solved).epsilon(0.02));
}

TEST_CASE("retime refuses options out of range, naming the option and the range expected") {
  const SpeedObjective objective(20);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  struct Bad {
    RetimeOptions options;
    std::string message;
  };
  std::vector<Bad> bad;
  // One push per case: a braced list of them makes g++ 12 warn of uninitialised vectors.
  auto add = [&bad](RetimeOptions options, std::string message) {
    bad.push_back({std::move(options), std::move(message)});
  };
  add({.duration = 0}, "RetimeOptions.duration = 0.0: expected > 0 and finite");
  add({.duration = -2}, "RetimeOptions.duration = -2.0: expected > 0 and finite");
  add({.duration = nan}, "RetimeOptions.duration = nan: expected > 0 and finite");
  add({.duration = inf}, "RetimeOptions.duration = inf: expected > 0 and finite");
  add({.duration = 2, .knot_spacing = 0}, "RetimeOptions.knot_spacing = 0.0: expected > 0 and finite");
  add({.duration = 2, .knot_spacing = nan}, "RetimeOptions.knot_spacing = nan: expected > 0 and finite");
  add({.duration = 2, .knot_spacing = 1e-300},
      "RetimeOptions.knot_spacing = 1e-300: expected >= duration / 4096 (0.000488281 s): it cuts the 2 s "
      "output into 2e+300 segments, at most 4096 are solved");
  add({.duration = 2, .knot_spacing = 2.0 / 4097}, "into 4097 segments, at most 4096");
  add({.duration = 1e6},
      "expected >= duration / 4096 (244.141 s): it cuts the 1e+06 s output into 1e+07 segments");
  add({.duration = 2, .samples_per_frame = 0}, "RetimeOptions.samples_per_frame = 0: expected 1 to 1000");
  add({.duration = 2, .max_iterations = 0}, "RetimeOptions.max_iterations = 0: expected >= 1");
  add({.duration = 2, .max_iterations = -5}, "RetimeOptions.max_iterations = -5: expected >= 1");
  add({.duration = 2, .function_tolerance = -1},
      "RetimeOptions.function_tolerance = -1.0: expected >= 0 and finite");
  add({.duration = 2, .gradient_tolerance = nan},
      "RetimeOptions.gradient_tolerance = nan: expected >= 0 and finite");
  add({.duration = 2, .pins = {{.source_time = nan, .output_time = 1}}},
      "time warp: pin 0 (source nan s at output 1 s): expected finite times");
  add({.duration = 2,
       .pins = {{.source_time = 1, .output_time = 0.5}, {.source_time = 2, .output_time = nan}}},
      "time warp: pin 1 (source 2 s at output nan s): expected finite times");
  for (const Bad& b : bad) {
    INFO(b.message);
    CHECK_THROWS_AS(retime(objective, b.options), std::invalid_argument);
    CHECK_THROWS_WITH(retime(objective, b.options), Catch::Matchers::Contains(b.message));
  }
}

TEST_CASE("holds play exactly at their speed over the segments they meet, whatever the objective prefers") {
  // The objective wants the stiff second (source 1 to 2 s) at 1x; a hold asks 1.5x from source 1.1 s.
  const SpeedObjective objective(200);
  const Hold hold{.source_start = 1.1, .output_start = 0.7, .length = 0.4, .speed = 1.5};
  const RetimeResult r = retime(objective, {.duration = 2.0, .holds = {hold}});
  INFO(r.message);
  CHECK(r.converged);
  CHECK(r.warp.at(2.0) == Approx(3.0).epsilon(1e-9));
  const auto [first, last] = held_segments(hold, r.warp.duration, r.warp.segments());
  const double h = r.warp.knot_spacing();
  CHECK(first * h <= hold.output_start + 1e-12);
  CHECK(last * h >= hold.output_start + hold.length - 1e-12);
  for (double t = first * h; t <= last * h; t += h / 7) {
    const WarpSample s = r.warp.sample(t);
    CHECK(s.p == Approx(1.1 + 1.5 * (t - 0.7)).margin(1e-9));
    CHECK(s.pdot == Approx(1.5).margin(1e-9));
    CHECK(s.pddot == Approx(0).margin(1e-6));
  }
  CHECK(r.warp.strictly_increasing());
}
