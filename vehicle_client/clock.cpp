#include "vehicle_client/clock.h"

#include <chrono>

namespace rsu::vehicle_client {

TimeNs system_clock_now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rsu::vehicle_client
