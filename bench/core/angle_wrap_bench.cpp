// SPDX-License-Identifier: Apache-2.0
// The frame assembler's unwrap (lidar/frame_assembler.cpp: every LiDAR point) wraps its azimuth less an
// unwrapped prediction that grows a turn per rotation, so its angles lie turns away from (-pi, pi]:
// wrap_angle there (its own exact remainder, common/angles.h) against a baseline in the same run, the
// library's std::remainder it stands for; and the clusterer's round (common/rounding.h) against
// std::round. The same angles, the same results (tests/common checks them bit for bit).
//   build/bench/core/rsu_benchmark --benchmark_filter='BM_(WrapAngle|Round)'
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "common/angles.h"
#include "common/rounding.h"

namespace {

using rsu::kPi;

// 2^16 points of an OS1-128 stream's unwrap an hour in (36,000 rotations at 10 Hz): the azimuth less the
// prediction, within a degree of a whole number of turns.
std::vector<double> unwrap_arguments() {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> off(-0.02, 0.02);
  std::vector<double> out(1 << 16);
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = -2.0 * kPi * static_cast<double>(36'000 + i / 2048) + off(rng);
  }
  return out;
}

// Sums f over the inputs, each iteration, and counts the inputs as items.
template <typename F>
void sum_over(benchmark::State& state, const std::vector<double>& in, F f) {
  for (auto _ : state) {
    double sum = 0.0;
    for (double x : in) {
      sum += f(x);
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * in.size()));
}

void BM_WrapAngleTurnsAway(benchmark::State& state) {
  sum_over(state, unwrap_arguments(), [](double a) { return rsu::wrap_angle(a); });
}
BENCHMARK(BM_WrapAngleTurnsAway);

void BM_WrapAngleTurnsAwayByRemainderBaseline(benchmark::State& state) {
  sum_over(state, unwrap_arguments(), [](double a) {
    const double r = std::remainder(a, 2.0 * kPi);
    return r <= -kPi ? r + 2.0 * kPi : r;
  });
}
BENCHMARK(BM_WrapAngleTurnsAwayByRemainderBaseline);

// The clusterer's argument: turns between a point's azimuth and where its laser should point, near 0.
std::vector<double> round_arguments() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> off(-0.01, 0.01);
  std::vector<double> out(1 << 16);
  for (double& x : out) {
    x = off(rng);
  }
  return out;
}

void BM_RoundHalfAway(benchmark::State& state) {
  sum_over(state, round_arguments(), [](double x) { return rsu::round_half_away(x); });
}
BENCHMARK(BM_RoundHalfAway);

void BM_RoundByStdRoundBaseline(benchmark::State& state) {
  sum_over(state, round_arguments(), [](double x) { return std::round(x); });
}
BENCHMARK(BM_RoundByStdRoundBaseline);

}  // namespace
