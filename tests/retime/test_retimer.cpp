#include <catch2/catch.hpp>

#include <cmath>

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

}  // namespace

TEST_CASE("integrate's gradient with respect to the controls matches finite differences") {
  const SpeedObjective objective(50);
  TimeWarp warp = initial_warp(3.0, 2.0, 16, {{.source_time = 1.5, .output_time = 1.1}});
  const int samples = grid_samples(warp, 30, 4);
  std::vector<double> gradient(warp.controls.size());
  integrate(objective, warp, samples, gradient.data());
  for (std::size_t j = 0; j < warp.controls.size(); ++j) {
    const double h = 1e-6;
    TimeWarp plus = warp, minus = warp;
    plus.controls[j] += h;
    minus.controls[j] -= h;
    const double fd = (integrate(objective, plus, samples) - integrate(objective, minus, samples)) / (2 * h);
    CHECK(gradient[j] == Approx(fd).epsilon(1e-5).margin(1e-6));
  }
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

TEST_CASE("pins hold exactly after the solve") {
  const SpeedObjective objective(20);
  const RetimeResult r = retime(objective, {.duration = 2.5, .pins = {{.source_time = 1.5, .output_time = 1.0}}});
  CHECK(r.converged);
  CHECK(r.warp.at(1.0) == Approx(1.5).epsilon(1e-9));
  CHECK(r.warp.at(2.5) == Approx(3.0).epsilon(1e-9));
}
