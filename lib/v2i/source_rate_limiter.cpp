// SPDX-License-Identifier: Apache-2.0
#include "v2i/source_rate_limiter.h"

namespace rsu::v2i {

RateDecision SourceRateLimiter::admit(std::string_view source, TimeNs now) {
  auto it = buckets_.find(std::string(source));
  if (it == buckets_.end()) {
    if (buckets_.size() >= config_.max_sources) {
      prune(now);
      if (buckets_.size() >= config_.max_sources) {
        return RateDecision::kTooManySources;
      }
    }
    it = buckets_.emplace(std::string(source), TokenBucket(config_.bucket, now)).first;
  }
  return it->second.try_take(now) ? RateDecision::kAllowed : RateDecision::kLimited;
}

void SourceRateLimiter::prune(TimeNs now) {
  std::erase_if(buckets_, [now](const auto& entry) { return entry.second.full_at() <= now; });
}

}  // namespace rsu::v2i
