// SPDX-License-Identifier: Apache-2.0
// sd_notify(3) messages to the service manager: READY, WATCHDOG, STOPPING, RELOADING (with
// MONOTONIC_USEC, as Type=notify-reload expects from systemd 253 on). Without NOTIFY_SOCKET (not run
// by systemd) every call is a no-op.
#pragma once

#include <chrono>
#include <optional>

namespace rsu::daemon {

void notify_ready();
void notify_stopping();
void notify_reloading();
void notify_watchdog();
void notify_status(const char* text);
// Half the watchdog timeout systemd expects pings within (WatchdogSec=), when a watchdog is enabled.
std::optional<std::chrono::microseconds> watchdog_ping_interval();

}  // namespace rsu::daemon
