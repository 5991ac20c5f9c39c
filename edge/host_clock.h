// SPDX-License-Identifier: Apache-2.0
// The common clock (docs/design.md §3) as the programs at the edge read it: the host's real-time
// clock, GNSS- or PTP-disciplined on a real RSU or vehicle, shared by every process in tests on one
// machine. The one place that reads it; lib/ never does (its callers pass the time in).
#pragma once

#include <chrono>

#include "common/time.h"

namespace rsu::edge {

// Nanoseconds since the Unix epoch.
inline TimeNs host_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rsu::edge
