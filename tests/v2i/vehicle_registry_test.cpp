// SPDX-License-Identifier: Apache-2.0
#include "v2i/vehicle_registry.h"

#include <gtest/gtest.h>

#include <string>

#include "test_announcement.h"

namespace rsu::v2i {
namespace {

using testing::make_announcement;

constexpr TimeNs kRegistryT0 = 1'000 * kNsPerSecond;
constexpr TimeNs kTick = 100 * kNsPerMs;  // announcements at 10 Hz

VehicleRegistryConfig roomy_config() {
  VehicleRegistryConfig c;
  c.rate_limit.bucket = {1000.0, 1000.0};  // rate limiting out of the way unless a test wants it
  return c;
}

TEST(SequenceNumbers, SerialArithmeticHandlesWrap) {
  EXPECT_TRUE(sequence_newer(2, 1));
  EXPECT_FALSE(sequence_newer(1, 2));
  EXPECT_FALSE(sequence_newer(5, 5));
  EXPECT_TRUE(sequence_newer(0, 0xFFFFFFFFU));
  EXPECT_TRUE(sequence_newer(3, 0xFFFFFFF0U));
  EXPECT_FALSE(sequence_newer(0xFFFFFFF0U, 3));
}

TEST(VehicleRegistry, AddsUpdatesAndRejectsOldSequences) {
  VehicleRegistry registry(roomy_config());
  EXPECT_EQ(registry.upsert(make_announcement(7, 10, kRegistryT0), "192.0.2.1", kRegistryT0),
            UpsertOutcome::kAdded);
  EXPECT_EQ(registry.upsert(make_announcement(7, 11, kRegistryT0 + kTick), "192.0.2.1", kRegistryT0 + kTick),
            UpsertOutcome::kUpdated);
  EXPECT_EQ(registry.upsert(make_announcement(7, 11, kRegistryT0 + kTick), "192.0.2.1", kRegistryT0 + kTick),
            UpsertOutcome::kDuplicateSequence);
  EXPECT_EQ(registry.upsert(make_announcement(7, 9, kRegistryT0 + kTick), "192.0.2.1", kRegistryT0 + kTick),
            UpsertOutcome::kStaleSequence);
  const RegisteredVehicle* v = registry.find(7, kRegistryT0 + kTick);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->announcement.sequence, 11U);
  EXPECT_EQ(v->announcements, 2U);
  EXPECT_EQ(v->first_heard, kRegistryT0);
  EXPECT_EQ(v->last_heard, kRegistryT0 + kTick);
  EXPECT_EQ(registry.stats().outcomes.count(UpsertOutcome::kDuplicateSequence), 1U);
  EXPECT_EQ(registry.stats().outcomes.count(UpsertOutcome::kStaleSequence), 1U);
  EXPECT_EQ(registry.stats().outcomes.total(), 4U);
}

TEST(VehicleRegistry, SequenceMayWrap) {
  VehicleRegistry registry(roomy_config());
  EXPECT_EQ(registry.upsert(make_announcement(7, 0xFFFFFFFFU, kRegistryT0), "s", kRegistryT0),
            UpsertOutcome::kAdded);
  EXPECT_EQ(registry.upsert(make_announcement(7, 0, kRegistryT0 + kTick), "s", kRegistryT0 + kTick),
            UpsertOutcome::kUpdated);
}

TEST(VehicleRegistry, ExpiresAfterTheSilenceTimeout) {
  VehicleRegistryConfig config = roomy_config();
  config.silence_timeout = 2 * kNsPerSecond;
  VehicleRegistry registry(config);
  registry.upsert(make_announcement(7, 1, kRegistryT0), "s7", kRegistryT0);
  registry.upsert(make_announcement(8, 1, kRegistryT0 + kNsPerSecond), "s8", kRegistryT0 + kNsPerSecond);

  const TimeNs edge = kRegistryT0 + 2 * kNsPerSecond;
  EXPECT_NE(registry.find(7, edge), nullptr);      // exactly the timeout: still there
  EXPECT_EQ(registry.find(7, edge + 1), nullptr);  // one ns later: silent
  EXPECT_NE(registry.find(8, edge + 1), nullptr);
  ASSERT_EQ(registry.active(edge + 1).size(), 1U);
  EXPECT_EQ(registry.active(edge + 1)[0]->announcement.vehicle_id, 8U);
  EXPECT_EQ(registry.size(), 2U);  // not removed until expire()
  EXPECT_EQ(registry.expire(edge + 1), 1U);
  EXPECT_EQ(registry.size(), 1U);
  EXPECT_EQ(registry.stats().expired, 1U);

  // Forgotten means a restarted vehicle (sequence back at 0) is welcome again.
  EXPECT_EQ(registry.upsert(make_announcement(7, 0, edge + 2), "s7", edge + 2), UpsertOutcome::kAdded);
}

TEST(VehicleRegistry, SilentEntryIsReplacedEvenBeforeExpire) {
  VehicleRegistry registry(roomy_config());
  registry.upsert(make_announcement(7, 500, kRegistryT0), "s", kRegistryT0);
  const TimeNs later = kRegistryT0 + 3 * kNsPerSecond;
  EXPECT_EQ(registry.upsert(make_announcement(7, 1, later), "s", later), UpsertOutcome::kAdded);
}

TEST(VehicleRegistry, RefusesNewVehiclesWhenFull) {
  VehicleRegistryConfig config = roomy_config();
  config.capacity = 3;
  VehicleRegistry registry(config);
  for (std::uint64_t id = 1; id <= 3; ++id) {
    EXPECT_EQ(registry.upsert(make_announcement(id, 1, kRegistryT0), std::to_string(id), kRegistryT0),
              UpsertOutcome::kAdded);
  }
  EXPECT_EQ(registry.upsert(make_announcement(4, 1, kRegistryT0), "s4", kRegistryT0),
            UpsertOutcome::kRegistryFull);
  // Known vehicles still update while full.
  EXPECT_EQ(registry.upsert(make_announcement(2, 2, kRegistryT0 + kTick), "s2", kRegistryT0 + kTick),
            UpsertOutcome::kUpdated);
  EXPECT_EQ(registry.stats().outcomes.count(UpsertOutcome::kRegistryFull), 1U);
  // Once vehicles 1 and 3 fall silent, their places are free.
  const TimeNs later = kRegistryT0 + 2 * kNsPerSecond + kTick / 2;
  EXPECT_EQ(registry.upsert(make_announcement(4, 1, later), "s4", later), UpsertOutcome::kAdded);
  EXPECT_EQ(registry.size(), 2U);
}

TEST(VehicleRegistry, RateLimitsPerSource) {
  VehicleRegistryConfig config;
  config.rate_limit.bucket = {20.0, 10.0};
  VehicleRegistry registry(config);
  std::uint32_t seq = 0;
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(
        is_accepted(registry.upsert(make_announcement(7, ++seq, kRegistryT0), "192.0.2.1", kRegistryT0)));
  }
  EXPECT_EQ(registry.upsert(make_announcement(7, ++seq, kRegistryT0), "192.0.2.1", kRegistryT0),
            UpsertOutcome::kRateLimited);
  // Another host is not affected.
  EXPECT_EQ(registry.upsert(make_announcement(8, 1, kRegistryT0), "192.0.2.2", kRegistryT0),
            UpsertOutcome::kAdded);
  // 20 tokens/s: one more after 50 ms.
  EXPECT_EQ(registry.upsert(make_announcement(7, ++seq, kRegistryT0 + 49 * kNsPerMs), "192.0.2.1",
                            kRegistryT0 + 49 * kNsPerMs),
            UpsertOutcome::kRateLimited);
  EXPECT_EQ(registry.upsert(make_announcement(7, ++seq, kRegistryT0 + 50 * kNsPerMs), "192.0.2.1",
                            kRegistryT0 + 50 * kNsPerMs),
            UpsertOutcome::kUpdated);
  EXPECT_EQ(registry.stats().outcomes.count(UpsertOutcome::kRateLimited), 2U);
}

TEST(VehicleRegistry, SizeAndSourceChangesAreAcceptedAndCounted) {
  VehicleRegistry registry(roomy_config());
  registry.upsert(make_announcement(7, 1, kRegistryT0), "192.0.2.1", kRegistryT0);
  VehicleAnnouncement towing = make_announcement(7, 2, kRegistryT0 + kTick);
  towing.size.length_m = 9.5;  // hitched a trailer
  EXPECT_EQ(registry.upsert(towing, "192.0.2.1", kRegistryT0 + kTick), UpsertOutcome::kUpdatedSizeChanged);
  EXPECT_EQ(registry.find(7, kRegistryT0 + kTick)->announcement.size.length_m, 9.5);
  VehicleAnnouncement tiny_change = make_announcement(7, 3, kRegistryT0 + 2 * kTick);
  tiny_change.size.length_m = 9.505;  // within the 1 cm tolerance
  EXPECT_EQ(registry.upsert(tiny_change, "192.0.2.1", kRegistryT0 + 2 * kTick), UpsertOutcome::kUpdated);

  EXPECT_EQ(registry.upsert(make_announcement(7, 4, kRegistryT0 + 3 * kTick), "198.51.100.9",
                            kRegistryT0 + 3 * kTick),
            UpsertOutcome::kUpdatedSizeChanged);  // back to 4.89 m, from a new address
  EXPECT_EQ(registry.find(7, kRegistryT0 + 3 * kTick)->source, "198.51.100.9");
  EXPECT_EQ(registry.stats().source_changes, 1U);
  EXPECT_EQ(registry.stats().outcomes.count(UpsertOutcome::kUpdatedSizeChanged), 2U);
}

TEST(VehicleRegistry, ActiveIsOrderedById) {
  VehicleRegistry registry(roomy_config());
  for (const std::uint64_t id : {42U, 7U, 19U}) {
    registry.upsert(make_announcement(id, 1, kRegistryT0), "s", kRegistryT0);
  }
  const auto active = registry.active(kRegistryT0);
  ASSERT_EQ(active.size(), 3U);
  EXPECT_EQ(active[0]->announcement.vehicle_id, 7U);
  EXPECT_EQ(active[1]->announcement.vehicle_id, 19U);
  EXPECT_EQ(active[2]->announcement.vehicle_id, 42U);
}

}  // namespace
}  // namespace rsu::v2i
