// SPDX-License-Identifier: Apache-2.0
// The clock the vehicle client reads, injected so that tests can step time. Times are nanoseconds of
// the common clock (docs/design.md §3); the default is the host's (edge/host_clock.h).
#pragma once

#include <functional>

#include "common/time.h"
#include "edge/host_clock.h"

namespace rsu::vehicle_client {

using Clock = std::function<TimeNs()>;

}  // namespace rsu::vehicle_client
