// SPDX-License-Identifier: Apache-2.0
// Counted, rate-limited warnings for bad input (issue #4: "each is counted and logged at a bounded
// rate"). A flood of garbage must not become a flood of log lines (journald would rate-limit the whole
// service and hide everything else): the first few of each reason are logged one by one, the rest
// only counted, and a summary of what was suppressed is logged every interval while more arrive.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>

namespace rsu::daemon {

class BadInputLog {
 public:
  BadInputLog(int log_first, std::chrono::steady_clock::duration summary_interval)
      : log_first_(log_first), interval_(summary_interval) {}

  // Counts one event; logs it (warn) if it is among the first `log_first` of its reason.
  void report(const std::string& reason, const std::string& detail);
  // Logs one summary line of the events suppressed since the last summary, if any and if the
  // interval has passed. Call from a periodic timer.
  void maybe_summarize(std::chrono::steady_clock::time_point now);
  void set_limits(int log_first, std::chrono::steady_clock::duration summary_interval) {
    log_first_ = log_first;
    interval_ = summary_interval;
  }

  std::uint64_t total(const std::string& reason) const {
    const auto it = counts_.find(reason);
    return it == counts_.end() ? 0 : it->second;
  }

 private:
  int log_first_;
  std::chrono::steady_clock::duration interval_;
  std::chrono::steady_clock::time_point last_summary_{};
  std::map<std::string, std::uint64_t> counts_;      // all time, by reason
  std::map<std::string, std::uint64_t> suppressed_;  // since the last summary
};

}  // namespace rsu::daemon
