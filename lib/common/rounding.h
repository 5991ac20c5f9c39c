// SPDX-License-Identifier: Apache-2.0
// std::round without the library call. x86-64's baseline has no rounding instruction (SSE4.1's roundsd),
// so std::round is a call; the clusterer rounds once per LiDAR point (perception/sweep_clusterer.cpp).
#pragma once

#include <cmath>
#include <cstdint>

namespace rsu {

// std::round, bit for bit: the nearest integer, halves away from zero, the sign of x kept (-0.3 -> -0).
// Below 2^52 the truncation by conversion is exact and so is |x| - trunc(|x|); above, x is an integer
// already (or infinite, or NaN) and takes the library call.
inline double round_half_away(double x) {
  const double magnitude = std::abs(x);
  if (!(magnitude < 0x1p52)) {
    return std::round(x);
  }
  double rounded = static_cast<double>(static_cast<std::int64_t>(magnitude));
  if (magnitude - rounded >= 0.5) {
    rounded += 1.0;
  }
  return std::copysign(rounded, x);
}

}  // namespace rsu
