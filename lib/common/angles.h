// SPDX-License-Identifier: Apache-2.0
// Angle helpers. Radians everywhere in code; yaw is counter-clockwise from +x (east) (docs/design.md §3).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace rsu {

constexpr double kPi = std::numbers::pi;

constexpr double deg_to_rad(double deg) {
  return deg * kPi / 180.0;
}
constexpr double rad_to_deg(double rad) {
  return rad * 180.0 / kPi;
}

// Both wraps run for every LiDAR point (decoding, frame assembly, clustering), most of them on angles
// less than a turn out of range. There one subtraction of 2 pi gives what std::remainder or std::fmod
// would, bit for bit: they return the exact a - n 2 pi, and for |a| between pi and 4 pi and n = +-1 the
// subtraction is exact (Sterbenz: x - y is exact when y / 2 <= x <= 2 y). Angles farther out take
// detail::remainder_two_pi or the library call (and NaN).

namespace detail {

// 2 pi split exactly as hi + lo, hi with 26 significant bits: n hi and n lo are exact for |n| < 2^26.
inline constexpr double kTwoPiHi =
    std::bit_cast<double>(std::bit_cast<std::uint64_t>(2.0 * kPi) & ~((std::uint64_t{1} << 27) - 1));
inline constexpr double kTwoPiLo = 2.0 * kPi - kTwoPiHi;

// std::remainder(a, 2 pi), bit for bit, for angles turns away (a frame assembler's unwrapped azimuth
// grows a turn per rotation), 3.4-3.8x quicker than the library call (BM_WrapAngleTurnsAway). With n the
// nearest whole number of turns, a - n hi is exact (Sterbenz: for |n| >= 1 it is within a factor 2 of a)
// and so one rounding of (a - n hi) - n lo gives the exact remainder. n is a / 2 pi (by a multiplication)
// made whole by adding and subtracting 1.5 * 2^52, with no division and no branch (a division and a
// branchy round made it slower than the library call): it is the nearest for certain when the result
// lies more than the computation's few 1e-15 inside (-pi, pi), as any other n leaves at least pi;
// otherwise, and beyond 2^25 rad, the library call.
inline double remainder_two_pi(double a) {
  if (std::abs(a) < 0x1p25) {
    constexpr double kWhole = 0x1.8p52;  // x + kWhole - kWhole is x rounded to a whole number (|x| < 2^51)
    const double n = (a * (1.0 / (2.0 * kPi)) + kWhole) - kWhole;
    const double r = (a - n * kTwoPiHi) - n * kTwoPiLo;
    if (std::abs(r) < kPi - 0x1p-40) {
      return r == 0.0 ? std::copysign(0.0, a) : r;  // the library's exact zero has the sign of a
    }
  }
  return std::remainder(a, 2.0 * kPi);
}

}  // namespace detail

// Wraps to (-pi, pi].
inline double wrap_angle(double a) {
  constexpr double kTwoPi = 2.0 * kPi;
  if (a >= -kPi && a <= kPi) {  // remainder's quotient is 0 (+-pi: a half, rounded to even)
    return a == -kPi ? kPi : a;
  }
  if (a > kPi && a < 3.0 * kPi) {
    return a - kTwoPi;
  }
  if (a < -kPi && a > -3.0 * kPi) {
    const double r = a + kTwoPi;
    return r == 0.0 ? -0.0 : r;  // remainder's exact zero keeps the sign of a
  }
  a = detail::remainder_two_pi(a);
  return a <= -kPi ? a + kTwoPi : a;
}

// Wraps to [0, 2 pi).
inline double wrap_angle_positive(double a) {
  constexpr double kTwoPi = 2.0 * kPi;
  if (a >= 0.0 && a < 2.0 * kTwoPi) {  // fmod's quotient is 0 or 1
    return a < kTwoPi ? a : a - kTwoPi;
  }
  a = std::fmod(a, kTwoPi);
  if (a < 0.0) {
    a += kTwoPi;
    return a < kTwoPi ? a : 0.0;  // a + 2 pi rounds to 2 pi for a just below 0 (above -4.4e-16)
  }
  return a;
}

// Smallest absolute difference between two angles, in [0, pi].
inline double angle_distance(double a, double b) {
  return std::abs(wrap_angle(a - b));
}

}  // namespace rsu
