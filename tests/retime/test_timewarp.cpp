#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>

#include "kg/retime/timewarp.hpp"

using namespace kg::retime;

TEST_CASE("a uniform warp plays at constant speed and meets its ends") {
  const TimeWarp warp = TimeWarp::uniform(4.0, 2.0, 7);
  CHECK(warp.segments() == 7);
  for (double t : {0.0, 0.3, 1.0, 1.77, 2.0}) {
    const WarpSample s = warp.sample(t);
    CHECK(s.p == Approx(2.0 * t).margin(1e-12));
    CHECK(s.pdot == Approx(2.0));
    CHECK(s.pddot == Approx(0.0).margin(1e-9));
  }
  CHECK(warp.strictly_increasing());
}

TEST_CASE(
    "warp sample weights are the derivatives of p with respect to the controls, and p's derivatives are "
    "consistent") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> step(0.05, 0.4);
  TimeWarp warp = TimeWarp::uniform(3.0, 2.5, 9);
  double c = -0.2;
  for (double& control : warp.controls) control = (c += step(rng));
  const double h = 1e-6;
  for (double t : {0.01, 0.4, 1.3, 2.2}) {
    const WarpSample s = warp.sample(t);
    CHECK(s.pdot == Approx((warp.at(t + h) - warp.at(t - h)) / (2 * h)).epsilon(1e-6));
    CHECK(s.pddot ==
          Approx((warp.sample(t + h).pdot - warp.sample(t - h).pdot) / (2 * h)).epsilon(1e-5).margin(1e-5));
    for (int i = 0; i < 4; ++i) {
      TimeWarp moved = warp;
      moved.controls[static_cast<std::size_t>(s.first + i)] += 1.0;
      const WarpSample m = moved.sample(t);
      CHECK(m.p - s.p == Approx(s.weight[i]));
      CHECK(m.pdot - s.pdot == Approx(s.weight_first[i]));
      CHECK(m.pddot - s.pddot == Approx(s.weight_second[i]));
    }
  }
}

TEST_CASE("max_pdot is the fastest playback within each segment, wherever in it that lies") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(0.01, 0.5);
  TimeWarp warp = TimeWarp::uniform(3.0, 2.5, 40);
  double c = -0.1;
  for (double& control : warp.controls) control = (c += step(rng));
  const double h = warp.knot_spacing();
  int inside = 0;  // segments whose fastest playback lies strictly inside
  for (int s = 0; s < warp.segments(); ++s) {
    double fastest = 0, where = 0;
    for (int k = 0; k <= 20000; ++k) {
      const double pdot = warp.sample((s + k / 20000.0) * h).pdot;
      if (pdot > fastest) fastest = pdot, where = k / 20000.0;
    }
    INFO("segment " << s << ", fastest at u = " << where);
    CHECK(warp.max_pdot(s) == Approx(fastest).epsilon(1e-8));
    CHECK(warp.max_pdot(s) >= fastest);
    inside += where > 0.01 && where < 0.99;
  }
  CHECK(inside > 3);
  CHECK(TimeWarp::uniform(4.0, 2.0, 7).max_pdot(3) == Approx(2.0));
}

TEST_CASE("initial_warp meets its ends and pins exactly and increases strictly") {
  const std::vector<Pin> pins{{.source_time = 1.5, .output_time = 0.5},
                              {.source_time = 2.0, .output_time = 1.5}};
  const TimeWarp warp = initial_warp(3.0, 2.0, 20, pins);
  CHECK(warp.at(0.0) == Approx(0.0).margin(1e-12));
  CHECK(warp.at(2.0) == Approx(3.0));
  CHECK(warp.at(0.5) == Approx(1.5));
  CHECK(warp.at(1.5) == Approx(2.0));
  CHECK(warp.strictly_increasing());
  for (double t = 0; t <= 2.0; t += 0.01) CHECK(warp.sample(t).pdot > 0);
}

TEST_CASE("initial_warp follows a starting playback, corrected onto the ends") {
  // Fast for the first output second (2.5 s of source), then slow (0.5 s in the next).
  const std::vector<Pin> playback{{0, 0}, {2.5, 1.0}, {3.0, 2.0}};
  const TimeWarp warp = initial_warp(3.0, 2.0, 40, {}, playback);
  CHECK(warp.at(0.0) == Approx(0.0).margin(1e-12));
  CHECK(warp.at(2.0) == Approx(3.0));
  CHECK(warp.at(1.0) == Approx(2.5).epsilon(0.02));
  CHECK(warp.sample(0.5).pdot == Approx(2.5).epsilon(0.02));
  CHECK(warp.sample(1.5).pdot == Approx(0.5).epsilon(0.02));
  CHECK(warp.strictly_increasing());
  CHECK_THROWS_WITH(initial_warp(3.0, 2.0, 40, {}, {{0, 0}, {2.0, 1.0}, {1.5, 1.5}, {3.0, 2.0}}),
                    Catch::Contains("sample 2 does not follow sample 1"));
  CHECK_THROWS_WITH(initial_warp(3.0, 2.0, 40, {}, {{0, 0}}), Catch::Contains("one sample"));
}

TEST_CASE("warp constraints refuse contradictory and misplaced pins, and segments too coarse for the pins") {
  auto message = [](auto&& call) {
    try {
      call();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  using Catch::Matchers::Contains;
  CHECK_THAT(message([] {
               warp_constraints(3, 2, 10, {{1.0, 0.5}, {0.8, 1.0}});
             }),
             Contains("contradictory pins"));
  CHECK_THAT(message([] {
               warp_constraints(3, 2, 10, {{1.0, 0.5}, {1.2, 0.5}});
             }),
             Contains("two pins at output"));
  CHECK_THAT(message([] { warp_constraints(3, 2, 10, {{1.0, 2.5}}); }), Contains("output time outside"));
  CHECK_THAT(message([] { warp_constraints(3, 2, 10, {{3.5, 1.0}}); }), Contains("source time outside"));
  CHECK_THAT(message([] { warp_constraints(3, -2, 10, {}); }), Contains("duration"));
  CHECK_THAT(message([] {
               initial_warp(3, 2, 1, {{0.3, 0.2}, {0.4, 0.25}, {2.9, 0.3}, {2.95, 1.9}});
             }),
             Contains("use shorter segments"));
}

TEST_CASE("holds fix the controls of the segments they meet to their line, holds that disagree are refused") {
  const Hold hold{.source_start = 1.0, .output_start = 0.55, .length = 0.3, .speed = 1.0};
  // 20 segments of 0.1 s: the hold meets segments 5 to 8 (0.5 to 0.9 s), whose controls are 5 to 11.
  CHECK(held_segments(hold, 2.0, 20) == std::pair<int, int>{5, 9});
  CHECK(held_segments({.source_start = 1.0, .output_start = 0.5, .length = 0.3}, 2.0, 20) ==
        std::pair<int, int>{5, 8});  // ending on a knot: not the segment after
  const WarpConstraints c = warp_constraints(3.0, 2.0, 20, {}, {hold});
  CHECK(c.A.rows() == 2 + 7);
  const TimeWarp warp = initial_warp(3.0, 2.0, 20, {}, {}, {hold});
  CHECK(warp.strictly_increasing());
  for (double t = 0.5; t <= 0.9; t += 0.01) CHECK(warp.sample(t).p == Approx(1.0 + (t - 0.55)).margin(1e-9));

  auto message = [](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  using Catch::Matchers::Contains;
  // Two lines one segment apart share controls.
  CHECK_THAT(message([&] {
               warp_constraints(3.0, 2.0, 20, {},
                                {hold, {.source_start = 1.5, .output_start = 0.95, .length = 0.2}});
             }),
             Contains("fix the same control to different values") && Contains("use shorter segments"));
  CHECK_THAT(message([] {
               warp_constraints(3.0, 2.0, 20, {},
                                {{.source_start = 1.0, .output_start = 1.9, .length = 0.3}});
             }),
             Contains("leave the warp"));
  CHECK_THAT(message([] {
               warp_constraints(3.0, 2.0, 20, {}, {{.source_start = 1.0, .output_start = 0.5, .length = 0}});
             }),
             Contains("positive length and speed"));
  CHECK_THAT(message([] {
               warp_constraints(3.0, 2.0, 20, {},
                                {{.source_start = NAN, .output_start = 0.5, .length = 0.2}});
             }),
             Contains("finite"));
}
