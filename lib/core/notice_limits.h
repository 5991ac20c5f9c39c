// SPDX-License-Identifier: Apache-2.0
// How many notices the RSU may send that tell a vehicle why it sends it nothing else (refusal_notices.h:
// an announcement refused; withheld_notices.h: a fix withheld): at most one per vehicle per
// NoticeConfig::per_vehicle_interval_s, and rate_per_s in all. A vehicle that keeps being refused or
// withheld learns why within the interval, and however many vehicles are owed one, what the RSU signs
// and sends stays bounded.
#pragma once

#include <cstdint>

#include "common/time.h"
#include "core/rsu_core_config.h"
#include "v2i/source_rate_limiter.h"
#include "v2i/token_bucket.h"

namespace rsu::core {

class NoticeLimits {
 public:
  // Throws std::invalid_argument unless the interval and the rate are > 0 (rsud's --check-config says so).
  explicit NoticeLimits(const NoticeConfig& config);

  bool enabled() const { return config_.enabled; }
  // Whether a notice for `vehicle_id` may go out at `now` (then it has taken its turn).
  bool admit(std::uint64_t vehicle_id, TimeNs now);
  // Forgets the vehicles whose turn has come round again.
  void prune(TimeNs now) { per_vehicle_.prune(now); }

 private:
  NoticeConfig config_;
  v2i::SourceRateLimiter per_vehicle_;
  v2i::TokenBucket overall_;
};

}  // namespace rsu::core
