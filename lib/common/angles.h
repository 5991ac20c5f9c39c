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

// Wraps to (-pi, pi].
inline double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

// Wraps to [0, 2 pi).
inline double wrap_angle_positive(double a) {
  a = std::fmod(a, 2.0 * kPi);
  return a < 0.0 ? a + 2.0 * kPi : a;
}

// Smallest absolute difference between two angles, in [0, pi].
inline double angle_distance(double a, double b) {
  return std::abs(wrap_angle(a - b));
}

}  // namespace rsu
