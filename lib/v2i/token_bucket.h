// SPDX-License-Identifier: Apache-2.0
// A token bucket (the classic traffic-shaping limiter): `burst` tokens at most, refilled at `rate`
// tokens per second; each admitted event takes one. Time is passed in.
#pragma once

#include "common/time.h"

namespace rsu::v2i {

struct TokenBucketConfig {
  // Announcements come at about 10 Hz: twice that sustained, and a burst of one second's worth for a
  // radio link that delivers a backlog at once.
  double rate_per_s = 20.0;
  double burst = 10.0;

  bool operator==(const TokenBucketConfig&) const = default;
};

class TokenBucket {
 public:
  // Starts full at time `now`.
  TokenBucket(const TokenBucketConfig& config, TimeNs now);

  // Takes one token if there is one. A clock that steps backwards refills nothing (and never panics).
  bool try_take(TimeNs now);

  // Tokens that would be available at `now`, without changing the bucket.
  double tokens_at(TimeNs now) const;

  // The time from which the bucket is full again (a full bucket is the same as a new one).
  TimeNs full_at() const;

 private:
  TokenBucketConfig config_;
  double tokens_;
  TimeNs last_;  // time tokens_ was valid
};

}  // namespace rsu::v2i
