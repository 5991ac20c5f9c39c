// SPDX-License-Identifier: Apache-2.0
#include "daemon/systemd_notify.h"

#include <systemd/sd-daemon.h>

#include <ctime>
#include <string>

namespace rsu::daemon {

void notify_ready() {
  sd_notify(0, "READY=1\nSTATUS=serving");
}
void notify_stopping() {
  sd_notify(0, "STOPPING=1\nSTATUS=stopping");
}

void notify_reloading() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  const long long usec = static_cast<long long>(ts.tv_sec) * 1000000LL + ts.tv_nsec / 1000;
  const std::string message = "RELOADING=1\nSTATUS=reloading\nMONOTONIC_USEC=" + std::to_string(usec);
  sd_notify(0, message.c_str());
}

void notify_watchdog() {
  sd_notify(0, "WATCHDOG=1");
}

void notify_status(const char* text) {
  sd_notifyf(0, "STATUS=%s", text);
}

std::optional<std::chrono::microseconds> watchdog_ping_interval() {
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) <= 0 || usec == 0)
    return std::nullopt;
  return std::chrono::microseconds(usec / 2);
}

}  // namespace rsu::daemon
