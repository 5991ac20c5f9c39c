// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "v2i/source_rate_limiter.h"
#include "v2i/token_bucket.h"

namespace rsu::v2i {
namespace {

constexpr TimeNs kT0 = 5 * kNsPerSecond;

TEST(TokenBucket, BurstThenRefillAtRate) {
  TokenBucket bucket({/*rate_per_s=*/4.0, /*burst=*/3.0}, kT0);
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_FALSE(bucket.try_take(kT0));
  // 4 tokens/s: one token after 250 ms, not before.
  EXPECT_FALSE(bucket.try_take(kT0 + 249 * kNsPerMs));
  EXPECT_TRUE(bucket.try_take(kT0 + 250 * kNsPerMs));
  EXPECT_FALSE(bucket.try_take(kT0 + 250 * kNsPerMs));
}

TEST(TokenBucket, RefillIsCappedAtBurst) {
  TokenBucket bucket({4.0, 3.0}, kT0);
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_DOUBLE_EQ(bucket.tokens_at(kT0 + 100 * kNsPerSecond), 3.0);
  const TimeNs later = kT0 + 100 * kNsPerSecond;
  int taken = 0;
  while (bucket.try_take(later)) {
    ++taken;
  }
  EXPECT_EQ(taken, 3);
}

TEST(TokenBucket, BackwardsClockRefillsNothing) {
  TokenBucket bucket({4.0, 1.0}, kT0);
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_FALSE(bucket.try_take(kT0 - 10 * kNsPerSecond));
  // Time is measured from the latest time seen, so stepping back does not earn tokens later either.
  EXPECT_FALSE(bucket.try_take(kT0 + 200 * kNsPerMs));
  EXPECT_TRUE(bucket.try_take(kT0 + 250 * kNsPerMs));
}

TEST(TokenBucket, FullAtIsWhenTheBucketRefilled) {
  TokenBucket bucket({4.0, 2.0}, kT0);
  EXPECT_EQ(bucket.full_at(), kT0);
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_TRUE(bucket.try_take(kT0));
  EXPECT_EQ(bucket.full_at(), kT0 + 500 * kNsPerMs);
}

TEST(SourceRateLimiter, SourcesHaveSeparateBuckets) {
  SourceRateLimiter limiter({{10.0, 2.0}, 16});
  EXPECT_EQ(limiter.admit("192.0.2.1", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("192.0.2.1", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("192.0.2.1", kT0), RateDecision::kLimited);
  EXPECT_EQ(limiter.admit("192.0.2.2", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("192.0.2.1", kT0 + 100 * kNsPerMs), RateDecision::kAllowed);
}

TEST(SourceRateLimiter, SourceTableIsBoundedAndIdleSourcesAreForgotten) {
  SourceRateLimiter limiter({{10.0, 2.0}, 3});
  EXPECT_EQ(limiter.admit("a", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("b", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("c", kT0), RateDecision::kAllowed);
  EXPECT_EQ(limiter.admit("d", kT0), RateDecision::kTooManySources);
  EXPECT_EQ(limiter.source_count(), 3U);
  // One token per 100 ms: after 100 ms every bucket (burst 2, one taken) is full again, i.e. idle.
  EXPECT_EQ(limiter.admit("d", kT0 + 100 * kNsPerMs), RateDecision::kAllowed);
  EXPECT_EQ(limiter.source_count(), 1U);
}

}  // namespace
}  // namespace rsu::v2i
