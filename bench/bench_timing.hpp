// Timing for the benchmarks: the best wall time of several runs of a callable, in seconds.
//
//   const double s = kg::bench::best_seconds(5, [&] { parse(text); });
#pragma once

#include <algorithm>
#include <chrono>
#include <limits>

namespace kg::bench {

template <class F>
double best_seconds(int runs, F&& f) {
  using Clock = std::chrono::steady_clock;
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return best;
}

}  // namespace kg::bench
