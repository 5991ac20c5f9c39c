// SPDX-License-Identifier: Apache-2.0
#include "daemon/bad_input_log.h"

#include <spdlog/spdlog.h>

namespace rsu::daemon {

void BadInputLog::report(const std::string& reason, const std::string& detail) {
  const std::uint64_t n = ++counts_[reason];
  if (n <= static_cast<std::uint64_t>(log_first_)) {
    spdlog::warn(
        "bad input ({}): {}{}", reason, detail,
        n == static_cast<std::uint64_t>(log_first_) ? " (further ones of this kind are only counted)" : "");
    return;
  }
  ++suppressed_[reason];
}

void BadInputLog::maybe_summarize(std::chrono::steady_clock::time_point now) {
  if (suppressed_.empty() || now - last_summary_ < interval_)
    return;
  std::string line;
  for (const auto& [reason, n] : suppressed_) {
    line += (line.empty() ? "" : ", ") + reason + " " + std::to_string(n) + " (total " +
            std::to_string(counts_[reason]) + ")";
  }
  spdlog::warn("bad input, not logged one by one since the last summary: {}", line);
  suppressed_.clear();
  last_summary_ = now;
}

}  // namespace rsu::daemon
