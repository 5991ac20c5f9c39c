// SPDX-License-Identifier: Apache-2.0
// Time on the project's one common clock (docs/design.md §3): nanoseconds, signed 64-bit.
// lib/ never reads a clock; callers pass TimeNs in.
#pragma once

#include <cstdint>

namespace rsu {

using TimeNs = std::int64_t;

constexpr TimeNs kNsPerUs = 1'000;
constexpr TimeNs kNsPerMs = 1'000'000;
constexpr TimeNs kNsPerSecond = 1'000'000'000;

constexpr double to_seconds(TimeNs t) {
  return static_cast<double>(t) * 1e-9;
}
constexpr TimeNs from_seconds(double s) {
  return static_cast<TimeNs>(s * 1e9 + (s >= 0 ? 0.5 : -0.5));
}

}  // namespace rsu
