// SPDX-License-Identifier: Apache-2.0
// spdlog set-up for rsud. On a terminal: coloured, with time stamps. Otherwise (systemd's journal, a
// file): no colours and no time stamps (journald adds its own), each line prefixed with the sd-daemon
// priority "<N>" (sd-daemon(3)), which journald turns into the entry's priority, then the level name.
#pragma once

#include <string>

namespace rsu::daemon {

void setup_logging(const std::string& level);

}  // namespace rsu::daemon
