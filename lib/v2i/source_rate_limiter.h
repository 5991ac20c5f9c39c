// SPDX-License-Identifier: Apache-2.0
// Per-source token-bucket rate limiting of incoming datagrams, with a bounded number of sources so a
// flood from many spoofed addresses cannot grow memory without limit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>

#include "common/time.h"
#include "v2i/token_bucket.h"

namespace rsu::v2i {

struct RateLimitConfig {
  TokenBucketConfig bucket;
  // Distinct sources tracked at once; a source whose bucket has refilled is forgotten (a fresh
  // bucket is identical), so this bounds only sources active within burst / rate seconds.
  std::size_t max_sources = 4096;

  bool operator==(const RateLimitConfig&) const = default;
};

enum class RateDecision : std::uint8_t { kAllowed, kLimited, kTooManySources };

class SourceRateLimiter {
 public:
  explicit SourceRateLimiter(const RateLimitConfig& config = {}) : config_(config) {}

  // `source` is whatever identifies a sender to the caller, e.g. "192.0.2.7" (per host, not per
  // port, so that changing ports does not earn fresh tokens).
  RateDecision admit(std::string_view source, TimeNs now);

  // Forgets sources whose buckets are full again at `now`.
  void prune(TimeNs now);

  std::size_t source_count() const { return buckets_.size(); }

 private:
  RateLimitConfig config_;
  std::unordered_map<std::string, TokenBucket> buckets_;
};

}  // namespace rsu::v2i
