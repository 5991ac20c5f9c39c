// SPDX-License-Identifier: Apache-2.0
// What may hide a car from a dense sensor (SweepOccluders::of, on the correction's path): a car 9 m out
// seen by 128 rings (15,000 points) and the sweep's other objects (a car passing in front of it, two
// beside, a wall behind: 30,000 points, 22,000 of them nearer than the car's far side), against a
// baseline in the same run: the same rule with an arctangent per candidate point, as SweepOccluders did
// before issue 16's pseudo-angles.
//   build/bench/core/rsu_benchmark --benchmark_filter='BM_Occluders'
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/angles.h"
#include "core/sweep_occluders.h"

namespace {

using rsu::core::HeldVehicle;
using rsu::perception::Detection;

constexpr rsu::TimeNs kRotation = 100'000'000;

// `n` points on the outline of a w x l box centred at (x, y), swept at t.
Detection box(double x, double y, double l, double w, int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  Detection d;
  d.sweep_time_ns = 5 * kRotation;
  for (int i = 0; i < n; ++i) {
    const bool side = i % 3 != 0;
    d.points.emplace_back(x + (side ? l * u(rng) : -l / 2), y + (side ? -w / 2 : w * u(rng)),
                          0.2 + 1.4 * (u(rng) + 0.5));
  }
  return d;
}

struct Scene {
  Detection car;
  std::vector<Detection> all;  // the car and the others, as a batch gives them
};

const Scene& scene() {
  static const Scene s = [] {
    std::mt19937 rng(3);
    Scene sc;
    sc.car = box(2.0, 9.0, 4.5, 1.8, 15'000, rng);
    sc.all = {sc.car, box(1.0, 4.5, 4.5, 1.8, 10'000, rng), box(-6.0, 4.0, 4.5, 1.8, 6'000, rng),
              box(8.0, 3.0, 4.5, 1.8, 6'000, rng), box(0.0, 25.0, 60.0, 0.2, 8'000, rng)};
    return sc;
  }();
  return s;
}

void BM_OccludersOfNearCar(benchmark::State& state) {
  rsu::core::SweepOccluders occluders(Eigen::Vector2d::Zero(), kRotation);
  occluders.add(scene().all);
  HeldVehicle held;
  held.points = scene().car.points;
  held.first_time = scene().car.sweep_time_ns;
  std::size_t taken = 0;
  for (auto _ : state) {
    taken = occluders.of(held).size();
    benchmark::DoNotOptimize(taken);
  }
  state.counters["occluder points"] = static_cast<double>(taken);
}
BENCHMARK(BM_OccludersOfNearCar)->Unit(benchmark::kMicrosecond);

// Baseline: the span from every point's arctangent, and an arctangent per candidate.
void BM_OccludersOfNearCarByAngleBaseline(benchmark::State& state) {
  const std::vector<Eigen::Vector3d>& car = scene().car.points;
  std::size_t taken = 0;
  for (auto _ : state) {
    const double ref = std::atan2(car.front().y(), car.front().x());
    double lo = 0.0, hi = 0.0, farthest = 0.0;
    for (const Eigen::Vector3d& p : car) {
      const double a = rsu::wrap_angle(std::atan2(p.y(), p.x()) - ref);
      lo = std::min(lo, a);
      hi = std::max(hi, a);
      farthest = std::max(farthest, p.head<2>().norm());
    }
    std::vector<Eigen::Vector2d> out;
    for (std::size_t d = 1; d < scene().all.size(); ++d) {
      for (const Eigen::Vector3d& p : scene().all[d].points) {
        if (!(p.head<2>().norm() < farthest))
          continue;
        const double a = rsu::wrap_angle(std::atan2(p.y(), p.x()) - ref);
        if (a >= lo - rsu::deg_to_rad(5.0) && a <= hi + rsu::deg_to_rad(5.0))
          out.push_back(p.head<2>());
      }
    }
    taken = out.size();
    benchmark::DoNotOptimize(taken);
  }
  state.counters["occluder points"] = static_cast<double>(taken);
}
BENCHMARK(BM_OccludersOfNearCarByAngleBaseline)->Unit(benchmark::kMicrosecond);

}  // namespace
