// The clock the vehicle client reads, injected so that tests can step time. Times are nanoseconds of
// the common clock (DESIGN.md §3): on a vehicle that is GNSS/PTP-disciplined system time, which is what
// system_clock_now() returns.
#pragma once

#include <functional>

#include "common/time.h"

namespace rsu::vehicle_client {

using Clock = std::function<TimeNs()>;

// Host system time, ns since the Unix epoch (the common clock of tests on one machine).
TimeNs system_clock_now();

}  // namespace rsu::vehicle_client
