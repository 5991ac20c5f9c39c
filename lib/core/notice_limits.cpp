// SPDX-License-Identifier: Apache-2.0
#include "core/notice_limits.h"

#include <stdexcept>
#include <string>

namespace rsu::core {
namespace {

const NoticeConfig& checked(const NoticeConfig& c) {
  if (!(c.per_vehicle_interval_s > 0.0) || !(c.rate_per_s > 0.0))
    throw std::invalid_argument("notices: the per-vehicle interval and the rate must be > 0");
  return c;
}

// One token per vehicle, refilled once per interval.
v2i::RateLimitConfig per_vehicle_limit(const NoticeConfig& c) {
  return {.bucket = {.rate_per_s = 1.0 / c.per_vehicle_interval_s, .burst = 1.0}, .max_sources = 4096};
}

}  // namespace

NoticeLimits::NoticeLimits(const NoticeConfig& config)
    : config_(checked(config)),
      per_vehicle_(per_vehicle_limit(config)),
      overall_({.rate_per_s = config.rate_per_s, .burst = config.rate_per_s}, 0) {}

bool NoticeLimits::admit(std::uint64_t vehicle_id, TimeNs now) {
  return per_vehicle_.admit("vehicle:" + std::to_string(vehicle_id), now) == v2i::RateDecision::kAllowed &&
         overall_.try_take(now);
}

}  // namespace rsu::core
