// SPDX-License-Identifier: Apache-2.0
#include "v2i/token_bucket.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rsu::v2i {

TokenBucket::TokenBucket(const TokenBucketConfig& config, TimeNs now)
    : config_(config), tokens_(std::max(0.0, config.burst)), last_(now) {}

double TokenBucket::tokens_at(TimeNs now) const {
  if (now <= last_) {
    return tokens_;
  }
  TimeNs elapsed = 0;
  if (__builtin_sub_overflow(now, last_, &elapsed)) {
    return std::max(0.0, config_.burst);
  }
  return std::min(std::max(0.0, config_.burst),
                  tokens_ + config_.rate_per_s * (static_cast<double>(elapsed) / 1e9));
}

bool TokenBucket::try_take(TimeNs now) {
  tokens_ = tokens_at(now);
  last_ = std::max(last_, now);
  // The tolerance absorbs rounding in rate * elapsed, so that exactly 1 / rate seconds earns a token.
  if (tokens_ >= 1.0 - 1e-9) {
    tokens_ = std::max(0.0, tokens_ - 1.0);
    return true;
  }
  return false;
}

TimeNs TokenBucket::full_at() const {
  const double missing = std::max(0.0, config_.burst - tokens_);
  if (missing == 0.0) {
    return last_;
  }
  if (!(config_.rate_per_s > 0.0)) {
    return std::numeric_limits<TimeNs>::max();
  }
  const double wait_ns = std::ceil(missing / config_.rate_per_s * 1e9);
  if (wait_ns >= static_cast<double>(std::numeric_limits<TimeNs>::max() - last_)) {
    return std::numeric_limits<TimeNs>::max();
  }
  return last_ + static_cast<TimeNs>(wait_ns);
}

}  // namespace rsu::v2i
