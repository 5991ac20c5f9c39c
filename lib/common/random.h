// SPDX-License-Identifier: Apache-2.0
// Counter-based random numbers: the value for (seed, stream, index) does not depend on the order in
// which values are drawn, so simulated noise is reproducible whatever the threading or culling.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace rsu {

// SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform in (0, 1), never exactly 0 or 1 (safe for log, and for log(1 - u) in normal_quantile). The top
// 53 bits all ones would give 1 - 2^-54, which rounds to 1.0 (normal_quantile(1.0) is NaN): that one
// value is held at the largest double below 1, and every other stays as it was.
constexpr double uniform_open01(std::uint64_t bits) {
  return std::min((static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0),
                  1.0 - 1.0 / 9007199254740992.0);
}

// A pair of independent standard normal variates for the key (seed, stream, index), Box-Muller.
struct NormalPair {
  double a;
  double b;
};

inline NormalPair standard_normal_pair(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  const std::uint64_t k = mix64(seed ^ mix64(stream ^ mix64(index)));
  const double u1 = uniform_open01(mix64(k));
  const double u2 = uniform_open01(mix64(k ^ 0x5851f42d4c957f2dULL));
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double phi = 2.0 * std::numbers::pi * u2;
  return {r * std::cos(phi), r * std::sin(phi)};
}

// Standard normal quantile by Acklam's rational approximation (relative error below 1.2e-9): a
// rational function of p in the central 95 %, of sqrt(-2 log p) in the tails. With uniform_open01 a
// normal variate per key at about a third of the cost of a Box-Muller pair (sim/lidar_simulator.cpp).
inline double normal_quantile(double p) {
  constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                          1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                          6.680131188771972e+01, -1.328068155288572e+01};
  constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                          -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                          3.754408661907416e+00};
  constexpr double kLow = 0.02425;
  if (p > kLow && p < 1.0 - kLow) {
    const double q = p - 0.5;
    const double r = q * q;
    return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
           (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  const double q = std::sqrt(-2.0 * std::log(p < 0.5 ? p : 1.0 - p));
  const double x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
                   ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  return p < 0.5 ? x : -x;
}

}  // namespace rsu
