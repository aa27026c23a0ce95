// The displacement map's uniform cubic B-splines: basis, continuity, what a key spacing can and
// cannot represent.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "kg/motion/bspline.hpp"
#include "kg/retarget/displacement.hpp"

using namespace kg;
using namespace kg::retarget;

namespace {

// The spline value at a fractional frame for controls c.
double spline_at(const Eigen::VectorXd& c, double frame, int frames, int spacing) {
  const motion::BasisAt b = motion::bspline_basis_at(frame, frames, spacing);
  double v = 0;
  for (int p = 0; p < 4; ++p) v += b.weight[static_cast<std::size_t>(p)] * c[b.first + p];
  return v;
}

// Fraction of a signal's energy (about its mean) the best spline of that spacing keeps.
double kept_energy(const Eigen::VectorXd& signal, int spacing) {
  const int frames = static_cast<int>(signal.size());
  DisplacementLayout layout(frames, {spacing});
  kg::motion::FrameMatrix values(frames, 1);
  values.col(0) = signal;
  const kg::motion::FrameMatrix fit = layout.sample(layout.fit(values));
  return fit.col(0).squaredNorm() / signal.squaredNorm();
}

}  // namespace

TEST_CASE("bspline: knot layout and control counts", "[bspline]") {
  CHECK(motion::bspline_segment_count(112, 4) == 28);  // ceil(111 / 4)
  CHECK(motion::bspline_control_count(112, 4) == 31);
  CHECK(motion::bspline_control_count(9, 4) == 5);  // frames 0..8: segments [0,4], [4,8]
  CHECK(motion::bspline_control_count(1, 4) == 4);  // one frame still has a whole segment
  CHECK(motion::bspline_control_count(10, 1) == 12);
  // The last frame sits at the end of the last segment, not at the start of a new one.
  const motion::BasisAt last = motion::bspline_basis(8, 9, 4);
  CHECK(last.first == 1);
  CHECK(last.weight[3] == Approx(1.0 / 6));
  // At a knot, the controls either side weigh 1/6, the one on it 4/6.
  const motion::BasisAt knot = motion::bspline_basis(4, 9, 4);
  CHECK(knot.first == 1);
  CHECK(knot.weight[0] == Approx(1.0 / 6));
  CHECK(knot.weight[1] == Approx(4.0 / 6));
  CHECK(knot.weight[2] == Approx(1.0 / 6));
  CHECK(knot.weight[3] == Approx(0.0).margin(1e-15));
  CHECK_THROWS_AS(motion::bspline_basis(9, 9, 4), std::out_of_range);
  CHECK_THROWS_AS(motion::bspline_control_count(0, 4), std::invalid_argument);
  CHECK_THROWS_AS(motion::bspline_control_count(10, 0), std::invalid_argument);
  CHECK_THROWS_AS(DisplacementLayout(10, {4, 0}), std::invalid_argument);
}

TEST_CASE("bspline: partition of unity and non-negative weights", "[bspline]") {
  for (int spacing : {1, 2, 3, 4, 8}) {
    for (double f = 0; f <= 37; f += 0.25) {
      const motion::BasisAt b = motion::bspline_basis_at(f, 38, spacing);
      double sum = 0;
      for (double w : b.weight) {
        CHECK(w >= 0);
        sum += w;
      }
      CHECK(sum == Approx(1.0).epsilon(1e-14));
      CHECK(b.first >= 0);
      CHECK(b.first + 3 < motion::bspline_control_count(38, spacing));
    }
  }
}

TEST_CASE("bspline: C2 continuity across knots", "[bspline]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const int frames = 41, spacing = 4;
  Eigen::VectorXd c(motion::bspline_control_count(frames, spacing));
  for (int i = 0; i < c.size(); ++i) c[i] = u(rng);
  const double h = 1e-3;
  for (int knot = spacing; knot < frames - 1; knot += spacing) {
    const double k = knot;
    // One-sided derivatives from inside each segment: value, slope and curvature agree.
    auto left = [&](double d) { return spline_at(c, k - d, frames, spacing); };
    auto right = [&](double d) { return spline_at(c, k + d, frames, spacing); };
    CHECK(left(1e-12) == Approx(right(1e-12)).margin(1e-9));
    const double d1_left = (3 * left(0) - 4 * left(h) + left(2 * h)) / (2 * h);
    const double d1_right = (-3 * right(0) + 4 * right(h) - right(2 * h)) / (2 * h);
    CHECK(d1_left == Approx(d1_right).margin(1e-5));
    const double d2_left = (left(0) - 2 * left(h) + left(2 * h)) / (h * h);
    const double d2_right = (right(0) - 2 * right(h) + right(2 * h)) / (h * h);
    CHECK(d2_left == Approx(d2_right).margin(2e-2));
    // The third derivative jumps at a knot in general (cubic pieces): C2, not C3.
  }
}

TEST_CASE("bspline: linear functions are reproduced exactly", "[bspline]") {
  for (int spacing : {1, 2, 4, 8}) {
    const int frames = 50;
    DisplacementLayout layout(frames, {spacing, spacing});
    // Controls on a line through their sites (frame (j - 1) k) give exactly that line.
    Eigen::VectorXd x(layout.unknown_count());
    for (int c = 0; c < 2; ++c)
      for (int j = 0; j < layout.control_count(c); ++j)
        x[layout.unknown(c, j)] = c == 0 ? 0.3 - 0.02 * layout.control_frame(c, j) : 1.5;
    const kg::motion::FrameMatrix d = layout.sample(x);
    for (int f = 0; f < frames; ++f) {
      CHECK(d(f, 0) == Approx(0.3 - 0.02 * f).margin(1e-12));
      CHECK(d(f, 1) == Approx(1.5).margin(1e-12));
    }
    // And the least-squares fit of a line is the line.
    kg::motion::FrameMatrix line(frames, 2);
    for (int f = 0; f < frames; ++f) line.row(f) << -0.7 + 0.013 * f, 2.0;
    const kg::motion::FrameMatrix back = layout.sample(layout.fit(line));
    CHECK((back - line).cwiseAbs().maxCoeff() < 1e-6);
  }
}

TEST_CASE("bspline: a key spacing cannot represent frequencies above it", "[bspline]") {
  const int frames = 240;
  for (int spacing : {2, 4, 8}) {
    Eigen::VectorXd fastest(frames), fast(frames), slow(frames);
    for (int f = 0; f < frames; ++f) {
      // Periods of k frames (one cycle per key), 2 k (the keys' Nyquist) and 8 k frames. The
      // cubic B-spline's response is sinc^4(pi k / period): 0, (2 / pi)^4 = 0.16, 0.86.
      fastest[f] = std::sin(2 * M_PI * f / spacing + 0.3);
      fast[f] = std::sin(2 * M_PI * f / (2.0 * spacing) + 0.3);
      slow[f] = std::sin(2 * M_PI * f / (8.0 * spacing) + 0.3);
    }
    INFO("spacing " << spacing);
    CHECK(kept_energy(fastest, spacing) < 0.05);
    CHECK(kept_energy(fast, spacing) < 0.3);
    CHECK(kept_energy(slow, spacing) > 0.97);
  }
  // The same fast signal passes a spline of denser keys.
  Eigen::VectorXd fast(frames);
  for (int f = 0; f < frames; ++f) fast[f] = std::sin(2 * M_PI * f / 16.0);
  CHECK(kept_energy(fast, 8) < 0.3);
  CHECK(kept_energy(fast, 2) > 0.97);
}

TEST_CASE("bspline: per-channel spacing, channel-major storage, apply", "[bspline]") {
  DisplacementLayout layout(20, {2, 4, 8});
  CHECK(layout.control_count(0) == 13);
  CHECK(layout.control_count(1) == 8);
  CHECK(layout.control_count(2) == 6);
  CHECK(layout.offset(1) == 13);
  CHECK(layout.offset(2) == 21);
  CHECK(layout.unknown_count() == 27);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(27);
  x[layout.unknown(1, 3)] = 6.0;  // channel 1's control sitting at frame 8
  kg::motion::FrameMatrix m1 = kg::motion::FrameMatrix::Constant(20, 3, 1.0);
  const kg::motion::FrameMatrix m = layout.apply(m1, x);
  CHECK(m(8, 1) == Approx(1 + 4.0));  // 6 * 4/6
  CHECK(m(4, 1) == Approx(1 + 1.0));  // 6 * 1/6 at the neighbouring knot
  CHECK(m(12, 1) == Approx(1 + 1.0));
  CHECK(m(0, 1) == Approx(1.0));  // two keys away: the edge of the control's support
  CHECK(m(16, 1) == Approx(1.0));
  CHECK(m(3, 1) > 1.0);  // inside it
  CHECK(m.col(0).isApproxToConstant(1.0));
  CHECK(m.col(2).isApproxToConstant(1.0));
  CHECK_THROWS_AS(layout.sample(Eigen::VectorXd::Zero(5)), std::invalid_argument);
}
