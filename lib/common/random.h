// SPDX-License-Identifier: Apache-2.0
// Counter-based random numbers: the value for (seed, stream, index) does not depend on the order in
// which values are drawn, so simulated noise is reproducible whatever the threading or culling.
#pragma once

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

// Uniform in (0, 1), never exactly 0 (safe for log).
constexpr double uniform_open01(std::uint64_t bits) {
  return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0);
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

}  // namespace rsu
