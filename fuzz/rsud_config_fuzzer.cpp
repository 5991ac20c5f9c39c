// SPDX-License-Identifier: Apache-2.0
// Fuzzes rsud's configuration parser (daemon/config.h): any text must give a configuration or a
// ConfigError naming the line and field, never a crash or another exception.
#include <cstddef>
#include <cstdint>
#include <string>

#include "daemon/config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const rsu::daemon::DaemonConfig config = rsu::daemon::parse_config(text, "/etc/rsud/rsud.yaml");
    (void)rsu::daemon::summarize(config);
  } catch (const rsu::daemon::ConfigError&) {
    // the documented failure
  }
  return 0;
}
