// SPDX-License-Identifier: Apache-2.0
// Angle helpers. Radians everywhere in code; yaw is counter-clockwise from +x (east) (docs/design.md §3).
#pragma once

#include <cmath>
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
// subtraction is exact (Sterbenz: x - y is exact when y / 2 <= x <= 2 y). Other angles (and NaN) take
// the library call.

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
  a = std::remainder(a, kTwoPi);
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
