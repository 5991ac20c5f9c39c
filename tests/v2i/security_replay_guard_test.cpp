// SPDX-License-Identifier: Apache-2.0
// Replay protection: the generation-time window's edges, the 64-wide sequence window (reordering,
// duplicates, wrap-around, restarts) against an independent reference, and bounded state.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <set>

#include "v2i/security/replay_guard.h"

namespace rsu::v2i::security {
namespace {

constexpr TimeNs kNow = 1'700'000'000 * kNsPerSecond;
constexpr TimeNs kMs = kNsPerMs;

KeyId signer(std::uint8_t n) {
  KeyId id{};
  id.fill(n);
  return id;
}

TEST(ReplayGuard, GenerationTimeWindowEdges) {
  ReplayConfig config;
  config.max_age = 1000 * kMs;
  config.max_future = 200 * kMs;
  ReplayGuard guard(config);
  std::uint32_t seq = 0;
  EXPECT_EQ(guard.admit(signer(1), ++seq, kNow - 1000 * kMs, kNow), ReplayVerdict::kFresh);  // edge: kept
  EXPECT_EQ(guard.admit(signer(1), ++seq, kNow - 1000 * kMs - 1, kNow), ReplayVerdict::kStale);
  EXPECT_EQ(guard.admit(signer(1), ++seq, kNow + 200 * kMs, kNow), ReplayVerdict::kFresh);  // edge: kept
  EXPECT_EQ(guard.admit(signer(1), ++seq, kNow + 200 * kMs + 1, kNow), ReplayVerdict::kFuture);
  // A refused message leaves no trace: the same numbers are still new.
  EXPECT_EQ(guard.admit(signer(1), 2, kNow, kNow), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.admit(signer(1), 4, kNow, kNow), ReplayVerdict::kFresh);
}

TEST(ReplayGuard, WindowEdgesAndDuplicates) {
  ReplayGuard guard({});
  EXPECT_EQ(guard.admit(signer(1), 1000, kNow, kNow), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.admit(signer(1), 1000, kNow, kNow), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.admit(signer(1), 1000 - 63, kNow - 10, kNow), ReplayVerdict::kFresh);  // last slot
  EXPECT_EQ(guard.admit(signer(1), 1000 - 63, kNow - 10, kNow), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.admit(signer(1), 1000 - 64, kNow - 10, kNow), ReplayVerdict::kTooOld);  // just outside
  // Another signer has its own window.
  EXPECT_EQ(guard.admit(signer(2), 1000, kNow, kNow), ReplayVerdict::kFresh);
  // A jump ahead by more than the window forgets everything below.
  EXPECT_EQ(guard.admit(signer(1), 1000 + 200, kNow + 1, kNow), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.admit(signer(1), 1000 + 200 - 63, kNow, kNow), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.admit(signer(1), 1000, kNow, kNow), ReplayVerdict::kTooOld);
}

TEST(ReplayGuard, SequenceWrapsModulo2To32) {
  ReplayGuard guard({});
  TimeNs t = kNow;
  for (std::uint32_t s = 0xFFFFFFF0U; s != 0x10U; ++s) {
    EXPECT_EQ(guard.admit(signer(1), s, ++t, kNow), ReplayVerdict::kFresh) << s;
  }
  EXPECT_EQ(guard.admit(signer(1), 0xFFFFFFFFU, kNow, kNow), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.admit(signer(1), 0U, kNow, kNow), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.admit(signer(1), 0x10U - 64U - 1U, kNow, kNow), ReplayVerdict::kTooOld);  // 0xFFFFFFCF
}

// Reordered delivery with duplicates, against a reference that unwraps the numbers into 64 bits and
// remembers every one: new when unseen and no more than 63 below the highest seen; otherwise too old
// when 64 or more below it, else a duplicate.
TEST(ReplayGuard, ReorderingMatchesAReference) {
  std::mt19937_64 rng(7);
  for (const std::uint32_t start : {0U, 0xFFFFFF00U}) {
    ReplayGuard guard({});
    std::set<std::int64_t> seen;
    std::int64_t highest = -1;
    int accepted = 0;
    int refused = 0;
    for (int k = 0; k < 20000; ++k) {
      // Mostly around the front, sometimes far back (beyond the window), sometimes a repeat.
      const std::int64_t front = static_cast<std::int64_t>(k);
      std::int64_t n = front - static_cast<std::int64_t>(rng() % 40);
      if (rng() % 10 == 0)
        n = front - static_cast<std::int64_t>(rng() % 150);
      n = std::max<std::int64_t>(n, 0);
      const bool expect_new = !seen.contains(n) && (highest < 0 || n > highest - 64);
      // Generation time follows the sender's order, as a real sender's does.
      const ReplayVerdict v =
          guard.admit(signer(1), static_cast<std::uint32_t>(start + n), kNow + n, kNow + n);
      ASSERT_EQ(v == ReplayVerdict::kFresh, expect_new) << "n " << n << " highest " << highest;
      if (expect_new) {
        seen.insert(n);
        highest = std::max(highest, n);
        ++accepted;
      } else {
        EXPECT_EQ(v, n <= highest - 64 ? ReplayVerdict::kTooOld : ReplayVerdict::kDuplicate);
        ++refused;
      }
    }
    EXPECT_GT(accepted, 1000);
    EXPECT_GT(refused, 1000);
  }
}

TEST(ReplayGuard, RestartIsAcceptedOnlyWithANewerGenerationTime) {
  ReplayGuard guard({});
  for (std::uint32_t s = 0; s < 100; ++s)
    ASSERT_EQ(guard.admit(signer(1), s, kNow + s, kNow + 100), ReplayVerdict::kFresh);
  // A replay of an old message: behind the window and not newer.
  EXPECT_EQ(guard.admit(signer(1), 5, kNow + 5, kNow + 100), ReplayVerdict::kTooOld);
  EXPECT_EQ(guard.admit(signer(1), 99, kNow + 99, kNow + 100), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.stats().restarts, 0U);
  // The sender rebooted: counter back at 0, generation time newer than anything accepted.
  EXPECT_EQ(guard.admit(signer(1), 0, kNow + 200, kNow + 200), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.stats().restarts, 1U);
  EXPECT_EQ(guard.admit(signer(1), 1, kNow + 201, kNow + 201), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.admit(signer(1), 1, kNow + 201, kNow + 201), ReplayVerdict::kDuplicate);
  // Pre-restart messages whose numbers now look new are refused: they were generated before it.
  EXPECT_EQ(guard.admit(signer(1), 50, kNow + 50, kNow + 201), ReplayVerdict::kTooOld);
}

TEST(ReplayGuard, StateIsBoundedByCapacityAndExpiry) {
  ReplayConfig config;
  config.max_signers = 3;
  config.signer_expiry = 10 * kNsPerSecond;
  ReplayGuard guard(config);
  for (std::uint8_t n = 1; n <= 5; ++n)
    EXPECT_EQ(guard.admit(signer(n), 7, kNow + n, kNow + n), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.tracked(), 3U);
  EXPECT_EQ(guard.stats().evictions, 2U);
  // Signers 1 and 2 were heard least recently and are gone: their state starts afresh.
  EXPECT_EQ(guard.admit(signer(5), 7, kNow + 5, kNow + 6), ReplayVerdict::kDuplicate);
  EXPECT_EQ(guard.admit(signer(1), 7, kNow + 1, kNow + 6), ReplayVerdict::kFresh);
  EXPECT_EQ(guard.tracked(), 3U);
  guard.expire(kNow + 4 + 10 * kNsPerSecond);  // signer 4 silent exactly the expiry: kept
  EXPECT_EQ(guard.tracked(), 3U);
  guard.expire(kNow + 7 + 10 * kNsPerSecond);
  EXPECT_EQ(guard.tracked(), 0U);
  EXPECT_EQ(guard.stats().expired, 3U);
}

// check() says what admit() would, and records nothing: on a random mix of fresh, reordered, repeated,
// old and restarted sequence numbers, stale and future times, over three signers.
TEST(ReplayGuard, CheckPredictsAdmitWithoutRecording) {
  ReplayConfig config;
  config.max_age = 1000 * kMs;
  config.max_future = 200 * kMs;
  ReplayGuard guard(config);
  ReplayGuard twin(config);  // sees admit() only: check() must not change what it says
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> pick(0, 99);
  std::array<std::uint32_t, 3> highest{100, 5000, 0xFFFFFFF0U};
  TimeNs now = kNow;
  std::array<int, static_cast<std::size_t>(ReplayVerdict::kCount)> seen{};
  for (int i = 0; i < 5000; ++i) {
    now += 3 * kMs;
    const auto k = static_cast<std::size_t>(pick(rng) % 3);
    const int r = pick(rng);
    std::uint32_t seq = highest[k] + 1;
    TimeNs t = now - 10 * kMs;
    if (r < 15) {
      seq = highest[k] - static_cast<std::uint32_t>(pick(rng));  // reordered, repeated or too old ...
      t = now - 300 * kMs;  // ... and generated before the newest: not a restart
    } else if (r < 18) {
      seq = static_cast<std::uint32_t>(pick(rng));  // a restart when newer than everything, else too old
      t = now - static_cast<TimeNs>(pick(rng)) * 20 * kMs;
    } else if (r < 21) {
      t = now - 1001 * kMs;
    } else if (r < 24) {
      t = now + 201 * kMs;
    }
    const ReplayVerdict predicted = guard.check(signer(static_cast<std::uint8_t>(k)), seq, t, now);
    ASSERT_EQ(guard.check(signer(static_cast<std::uint8_t>(k)), seq, t, now), predicted);  // nothing recorded
    const ReplayVerdict admitted = guard.admit(signer(static_cast<std::uint8_t>(k)), seq, t, now);
    ASSERT_EQ(predicted, admitted) << "message " << i;
    ASSERT_EQ(twin.admit(signer(static_cast<std::uint8_t>(k)), seq, t, now), admitted) << "message " << i;
    if (admitted == ReplayVerdict::kFresh && r >= 15)
      highest[k] = seq;  // the next number, or a restart
    ++seen[static_cast<std::size_t>(admitted)];
  }
  for (std::size_t v = 0; v < seen.size(); ++v)
    EXPECT_GT(seen[v], 0) << to_string(static_cast<ReplayVerdict>(v));  // every verdict exercised
}

}  // namespace
}  // namespace rsu::v2i::security
