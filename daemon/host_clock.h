// The common clock (DESIGN.md §3) as rsud reads it: the host's real-time clock, GNSS/PTP-disciplined
// on a real RSU.
#pragma once

#include <chrono>

#include "common/time.h"

namespace rsu::daemon {

inline TimeNs now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rsu::daemon
