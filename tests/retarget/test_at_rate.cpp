// A solve at 30 Hz written at 120 Hz (at_rate.hpp): exact at the solve's frames, the solve's own
// B-spline displacement between them, the source's detail kept.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "kg/motion/bspline.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retarget/at_rate.hpp"
#include "kg/retarget/displacement.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/synth/synthesize.hpp"

namespace {

using Catch::Matchers::Contains;
using kg::motion::Motion;
using kg::retarget::DisplacementLayout;
using kg::retarget::result_at_rate;
using kg::retarget::Target;

struct Solved {
  Motion fine, coarse, initial, result;
  Target target;
  DisplacementLayout layout;
  Eigen::VectorXd controls;
  Eigen::MatrixXd shift;  // frames x channels the initial estimate adds to the scaled source
};

// A 120 Hz walk, the same walk at 30 Hz, an initial estimate with a smooth shift and a result
// displaced by a random spline with keys every 4 frames of 30 Hz.
Solved solved_walk() {
  Solved s;
  s.fine = kg::synth::synthesize_walk({.steps = 4, .speed = 1.3, .fps = 120}).motion;
  s.coarse = kg::motion::resample(s.fine, 30);
  s.target = kg::retarget::uniform_target(s.fine.skeleton, 0.7);
  const Motion scaled = kg::retarget::scale_translation(s.coarse, s.target);
  s.initial = scaled;
  s.initial.skeleton = s.target.skeleton;
  s.shift = Eigen::MatrixXd::Zero(scaled.frame_count(), scaled.values.cols());
  for (int f = 0; f < scaled.frame_count(); ++f) s.shift(f, 0) = 0.05 * std::sin(f / 9.0);  // root x
  s.initial.values += s.shift;
  const int channels = static_cast<int>(scaled.values.cols());
  s.layout =
      DisplacementLayout(scaled.frame_count(), std::vector<int>(static_cast<std::size_t>(channels), 4));
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-0.05, 0.05);
  s.controls.resize(s.layout.unknown_count());
  for (Eigen::Index i = 0; i < s.controls.size(); ++i) s.controls[i] = uniform(random);
  s.result = s.initial;
  s.result.values = s.layout.apply(s.initial.values, s.controls);
  return s;
}

double spline_at(const DisplacementLayout& layout, const Eigen::VectorXd& x, int channel, double frame) {
  const kg::motion::BasisAt b = kg::motion::bspline_basis_at(frame, layout.frames(), layout.spacing(channel));
  double value = 0;
  for (int i = 0; i < 4; ++i)
    value += b.weight[static_cast<std::size_t>(i)] * x[layout.unknown(channel, b.first + i)];
  return value;
}

}  // namespace

TEST_CASE("result_at_rate: a 30 Hz solve written at 120 Hz", "[retarget][at_rate]") {
  const Solved s = solved_walk();
  const kg::retarget::ResultAtRate r = result_at_rate(s.fine, s.coarse, s.initial, s.result, s.target);
  REQUIRE(r.result.frame_count() == s.fine.frame_count());
  CHECK(r.result.fps == 120);
  CHECK(r.result.skeleton == s.target.skeleton);
  const Motion scaled_fine = kg::retarget::scale_translation(s.fine, s.target);
  const int channels = static_cast<int>(s.fine.values.cols());

  SECTION("every solve frame is the solve's result") {
    double worst = 0;
    for (int f = 0; f < s.coarse.frame_count(); ++f)
      worst = std::max(worst, (r.result.values.row(4 * f) - s.result.values.row(f)).cwiseAbs().maxCoeff());
    CHECK(worst < 1e-9);
  }
  SECTION("between them, the source at 120 Hz plus the solve's own spline") {
    // Away from the first and last frames, where the interpolant's end slopes are estimated.
    double worst = 0, largest = 0;
    for (int g = 40; g + 40 < s.fine.frame_count(); ++g)
      for (int c = 0; c < channels; ++c) {
        const double d = spline_at(s.layout, s.controls, c, g / 4.0);
        const double shift = c == 0 ? 0.05 * std::sin(g / 36.0) : 0.0;
        worst = std::max(worst, std::abs(r.result.values(g, c) - scaled_fine.values(g, c) - d - shift));
        largest = std::max(largest, std::abs(d));
      }
    INFO("worst " << worst << " of displacements up to " << largest);
    CHECK(largest > 0.02);
    // The spline exactly; the shift sin(f / 9), sampled every 30 Hz frame, to the interpolant's
    // O(h^4) accuracy.
    CHECK(worst < 1e-5);
  }
  SECTION("the initial estimate comes along at the same rate") {
    for (int f = 0; f < s.coarse.frame_count(); ++f)
      CHECK((r.initial.values.row(4 * f) - s.initial.values.row(f)).cwiseAbs().maxCoeff() < 1e-9);
  }
  SECTION("the last 120 Hz frames past the last 30 Hz frame continue the displacement") {
    CHECK(r.result.values.allFinite());
    const int last = r.result.frame_count() - 1;
    const double step = (r.result.values.row(last) - scaled_fine.values.row(last)).cwiseAbs().maxCoeff();
    CHECK(step < 1.0);
  }
}

TEST_CASE("result_at_rate: the same rate passes the result unchanged", "[retarget][at_rate]") {
  const Solved s = solved_walk();
  const kg::retarget::ResultAtRate r = result_at_rate(s.coarse, s.coarse, s.initial, s.result, s.target);
  CHECK(r.result.values == s.result.values);
  CHECK(r.initial.values == s.initial.values);
}

TEST_CASE("result_at_rate: another clip or layout is refused", "[retarget][at_rate]") {
  const Solved s = solved_walk();
  const Motion half = kg::motion::frame_range(s.fine, 0, s.fine.frame_count() / 2);
  CHECK_THROWS_WITH(result_at_rate(half, s.coarse, s.initial, s.result, s.target),
                    Contains("not the same clip at two rates"));
  Motion shorter = s.result;
  shorter.values.conservativeResize(shorter.frame_count() - 1, Eigen::NoChange);
  CHECK_THROWS_WITH(result_at_rate(s.fine, s.coarse, s.initial, shorter, s.target),
                    Contains("they must agree"));
}

TEST_CASE("constraints_at_rate: a 30 Hz plant checked at every 120 Hz frame of its time",
          "[retarget][at_rate]") {
  using kg::retarget::Constraint;
  using kg::retarget::ConstraintSet;
  using kg::retarget::Sample;
  ConstraintSet set;
  Constraint plant{.kind = "position", .label = "toe plant", .params = {0, 0, 0, 1, 1, 1}};
  Constraint skid{.kind = "same_place", .label = "toe non-skid"};
  Constraint moving{.kind = "position", .label = "moving target", .params = {0, 0, 0, 1, 1, 1}};
  Constraint once{.kind = "position", .label = "one instant", .params = {0, 0, 0, 1, 1, 1}};
  for (int f = 10; f <= 15; ++f) plant.samples.push_back({.frames = {f}});
  for (int f = 10; f < 15; ++f) skid.samples.push_back({.frames = {f, f + 1}});
  for (int f = 20; f <= 21; ++f)
    moving.samples.push_back({.frames = {f}, .params = {f * 1.0, 0, 0, 1, 1, 1}});
  once.samples.push_back({.frames = {7}});
  set.constraints = {plant, skid, moving, once};

  const ConstraintSet at120 = kg::retarget::constraints_at_rate(set, 30, 120, 200);
  REQUIRE(at120.constraints.size() == 4);
  const auto& p = at120.constraints[0].samples;
  REQUIRE(p.size() == 21);  // frames 40 .. 60
  for (int i = 0; i < 21; ++i) CHECK(p[static_cast<std::size_t>(i)].frames == std::vector<int>{40 + i});
  // The pairs keep their 1/30 s apart (4 frames at 120 Hz), inside the plant's time.
  const auto& s = at120.constraints[1].samples;
  REQUIRE(s.size() == 20);  // instants 41 .. 60 (40 against itself says nothing)
  CHECK(s.front().frames == std::vector<int>{40, 41});
  CHECK(s[3].frames == std::vector<int>{40, 44});
  CHECK(s.back().frames == std::vector<int>{56, 60});
  // A per-sample target moves linearly between its samples.
  const auto& m = at120.constraints[2].samples;
  REQUIRE(m.size() == 5);
  CHECK(m[2].frames == std::vector<int>{82});
  CHECK(m[2].params[0] == Approx(20.5));
  CHECK(at120.constraints[3].samples.size() == 1);
  CHECK(at120.constraints[3].samples[0].frames == std::vector<int>{28});

  // The same rate is the same set; the frames written bound the frames read.
  CHECK(kg::retarget::constraints_at_rate(set, 30, 30, 200).constraints[1].samples.size() == 5);
  const ConstraintSet short_clip = kg::retarget::constraints_at_rate(set, 30, 120, 50);
  for (const auto& c : short_clip.constraints)
    for (const Sample& sample : c.samples)
      for (int f : sample.frames) CHECK(f < 50);
  CHECK_THROWS_WITH(kg::retarget::constraints_at_rate(set, 0, 120, 10), Contains("positive rates"));
}

TEST_CASE("constraints_at_rate: a 120 Hz plant checked at 30 Hz reads consecutive frames",
          "[retarget][at_rate]") {
  using kg::retarget::Constraint;
  using kg::retarget::ConstraintSet;
  ConstraintSet set;
  Constraint skid{.kind = "same_place", .label = "toe non-skid"};
  Constraint brief{.kind = "same_place", .label = "brief non-skid"};
  Constraint plant{.kind = "position", .label = "brief plant", .params = {0, 0, 0, 1, 1, 1}};
  for (int f = 40; f < 60; ++f) skid.samples.push_back({.frames = {f, f + 1}});
  for (int f = 101; f < 103; ++f) brief.samples.push_back({.frames = {f, f + 1}});
  for (int f = 101; f <= 103; ++f) plant.samples.push_back({.frames = {f}});
  set.constraints = {skid, brief, plant};

  const ConstraintSet at30 = kg::retarget::constraints_at_rate(set, 120, 30, 50);
  // The brief plant (frames 101-103, 1/40 s) holds no two 30 Hz frames: its non-skid is left out;
  // its position constraint stays, at the frame nearest its middle (102 / 4).
  REQUIRE(at30.constraints.size() == 2);
  CHECK(at30.constraints[0].label == "toe non-skid");
  CHECK(at30.constraints[1].label == "brief plant");
  const auto& s = at30.constraints[0].samples;
  REQUIRE(s.size() == 5);  // instants 11 .. 15 against the frame before, inside frames 10 .. 15
  for (std::size_t i = 0; i < s.size(); ++i)
    CHECK(s[i].frames == std::vector<int>{10 + static_cast<int>(i), 11 + static_cast<int>(i)});
  REQUIRE(at30.constraints[1].samples.size() == 1);
  CHECK(at30.constraints[1].samples[0].frames == std::vector<int>{26});
}
