// SPDX-License-Identifier: Apache-2.0
// CorrectionFilter: ordering per RSU, restart of an RSU, sequence wrap-around and bounded memory (in
// insecure mode: those are about ordering), then signed mode: only genuine, fresh RSU corrections.
#include "vehicle/correction_filter.h"

#include <gtest/gtest.h>

#include "../v2i/test_keys.h"
#include "v2i/message_signer.h"
#include "v2i/wire_codec.h"

namespace rsu::vehicle {
namespace {

constexpr std::uint64_t kFilteredVehicle = 99;
constexpr TimeNs kNow = 1'700'000'000 * kNsPerSecond;

CorrectionFilterConfig insecure(std::size_t max_tracked_rsus) {
  return {kFilteredVehicle,
          max_tracked_rsus,
          {.mode = v2i::SecurityMode::kInsecure, .replay = {}, .verify_within = {}},
          {}};
}

v2i::Correction correction(std::uint64_t rsu_id, std::uint32_t sequence, TimeNs sweep_time) {
  v2i::Correction c;
  c.rsu_id = rsu_id;
  c.vehicle_id = kFilteredVehicle;
  c.sequence = sequence;
  c.sweep_time = sweep_time;
  c.pose = {1.0, 2.0, 0.5};
  c.pose_covariance = Eigen::Matrix3d::Identity() * 0.01;
  return c;
}

// Unsigned.
std::vector<std::uint8_t> datagram(std::uint64_t rsu_id, std::uint32_t sequence, TimeNs sweep_time) {
  return v2i::encode_v2i_message(correction(rsu_id, sequence, sweep_time));
}

TEST(CorrectionFilter, OrderIsKeptPerRsu) {
  CorrectionFilter filter(insecure(64));
  v2i::Correction out;
  EXPECT_EQ(filter.check(datagram(1, 10, 1000), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(out.sequence, 10U);
  // Another RSU has its own counter and clock of sweeps: an earlier sweep from it is news.
  EXPECT_EQ(filter.check(datagram(2, 3, 500), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 10, 1000), kNow, out), CorrectionVerdict::kDuplicate);
  EXPECT_EQ(filter.check(datagram(1, 9, 900), kNow, out), CorrectionVerdict::kStale);
  EXPECT_EQ(filter.check(datagram(1, 11, 1100), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kAccepted), 3U);
  EXPECT_EQ(filter.counts().total(), 5U);
  EXPECT_EQ(filter.sequence_restarts(), 0U);
}

TEST(CorrectionFilter, ARestartedRsuIsHeardAgain) {
  CorrectionFilter filter(insecure(64));
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 500, 5000), kNow, out), CorrectionVerdict::kAccepted);
  // The daemon restarted: its counter begins again, its sweeps are later.
  EXPECT_EQ(filter.check(datagram(1, 0, 9000), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 1, 9100), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.sequence_restarts(), 1U);
}

TEST(CorrectionFilter, SequenceWrapAroundIsNotARestart) {
  CorrectionFilter filter(insecure(64));
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 0xFFFFFFFFU, 100), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 0, 200), kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.sequence_restarts(), 0U);
}

TEST(CorrectionFilter, ForgetsTheLeastRecentlyHeardRsuBeyondItsCapacity) {
  CorrectionFilter filter(insecure(2));
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 1, 100), kNow, out), CorrectionVerdict::kAccepted);
  ASSERT_EQ(filter.check(datagram(2, 1, 100), kNow, out), CorrectionVerdict::kAccepted);
  ASSERT_EQ(filter.check(datagram(3, 1, 100), kNow, out), CorrectionVerdict::kAccepted);  // RSU 1 forgotten
  // RSU 1's duplicate is no longer recognised (memory stays bounded) ...
  EXPECT_EQ(filter.check(datagram(1, 1, 100), kNow, out), CorrectionVerdict::kAccepted);
  // ... which evicted RSU 2, while RSU 3 is still remembered.
  EXPECT_EQ(filter.check(datagram(3, 1, 100), kNow, out), CorrectionVerdict::kDuplicate);
}

TEST(CorrectionFilter, TruncatedBytesAreGarbage) {
  CorrectionFilter filter(insecure(64));
  v2i::Correction out;
  const std::vector<std::uint8_t> whole = datagram(1, 1, 100);
  ASSERT_GT(whole.size(), 10U);
  // The correction is one length-delimited field of the envelope: every strict prefix either cuts it
  // (a parse error) or leaves it out (no body), so every one is garbage.
  for (std::size_t n = 0; n < whole.size(); ++n) {
    EXPECT_EQ(filter.check({whole.data(), n}, kNow, out), CorrectionVerdict::kGarbage) << n << " bytes";
  }
  EXPECT_EQ(filter.check(whole, kNow, out), CorrectionVerdict::kAccepted);
}

// Signed mode: the RSU's signature is checked before anything else; forged, replayed, unsigned, stale
// and mis-attributed corrections are refused and counted, and the genuine flow keeps working.
TEST(CorrectionFilter, SignedModeTakesOnlyGenuineFreshCorrections) {
  const v2i::security::SigningKey rsu_key = key_from(1);
  const v2i::security::SigningKey forger = key_from(2);
  CorrectionFilterConfig config{kFilteredVehicle, 64, {}, {}};
  config.trust_list.add({rsu_key.public_key(), v2i::security::SignerRole::kRsu, {1}});
  CorrectionFilter filter(config);
  v2i::MessageSigner rsu(rsu_key);
  v2i::MessageSigner forged(forger);
  v2i::Correction out;
  const std::vector<std::uint8_t> first = rsu.encode(correction(1, 1, kNow - 30 * kNsPerMs), kNow);
  EXPECT_EQ(filter.check(first, kNow, out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(out.sequence, 1U);
  EXPECT_EQ(filter.check(forged.encode(correction(1, 2, kNow), kNow), kNow, out),
            CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.check(first, kNow + 10, out), CorrectionVerdict::kNotAuthentic);            // replayed
  EXPECT_EQ(filter.check(datagram(1, 3, kNow), kNow, out), CorrectionVerdict::kNotAuthentic);  // unsigned
  EXPECT_EQ(filter.check(rsu.encode(correction(2, 4, kNow), kNow), kNow, out),
            CorrectionVerdict::kNotAuthentic);  // RSU 1's key speaking for RSU 2
  EXPECT_EQ(filter.check(rsu.encode(correction(1, 5, kNow), kNow - 2 * kNsPerSecond), kNow, out),
            CorrectionVerdict::kNotAuthentic);  // generated 2 s ago
  // The genuine flow goes on.
  EXPECT_EQ(filter.check(rsu.encode(correction(1, 6, kNow + 50), kNow + 60), kNow + 70, out),
            CorrectionVerdict::kAccepted);
  EXPECT_EQ(out.sequence, 6U);
  const auto& a = filter.authentication_counts();
  EXPECT_EQ(a.count(v2i::AuthVerdict::kAccepted), 2U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kUnknownSigner), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kDuplicate), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kUnsigned), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kWrongSubject), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kStale), 1U);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kNotAuthentic), 5U);
}

// An RSU's advertisement reaches the vehicle authenticated like a correction: it is kept (whether that
// RSU withholds its fixes, and why), never taken for a correction; a forged one is not believed.
TEST(CorrectionFilter, AdvertisementSayingFixesAreWithheldIsKeptNotFused) {
  const v2i::security::SigningKey rsu_key = key_from(1);
  CorrectionFilterConfig config{kFilteredVehicle, 64, {}, {}};
  config.trust_list.add({rsu_key.public_key(), v2i::security::SignerRole::kRsu, {1}});
  CorrectionFilter filter(config);
  v2i::MessageSigner rsu(rsu_key);
  v2i::MessageSigner forged(key_from(2));
  v2i::RsuAdvertisement ad;
  ad.rsu_id = 1;
  ad.fixes_withheld = v2i::FixesWithheld::kMountMoved;
  ad.mount_error_at_radius_m = 0.44;
  v2i::Correction out;
  EXPECT_EQ(filter.check(rsu.encode(ad, kNow), kNow, out), CorrectionVerdict::kAdvertisement);
  EXPECT_EQ(filter.last_advertisement().fixes_withheld, v2i::FixesWithheld::kMountMoved);
  EXPECT_EQ(filter.last_advertisement().mount_error_at_radius_m, 0.44);
  ad.fixes_withheld = v2i::FixesWithheld::kNone;
  EXPECT_EQ(filter.check(forged.encode(ad, kNow), kNow, out), CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.last_advertisement().fixes_withheld, v2i::FixesWithheld::kMountMoved);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kAdvertisement), 1U);
}

// An RSU's notice that it withheld this vehicle's fix is authenticated like a correction: kept and
// counted (never taken for a correction); one for another vehicle, unsigned, forged, signed by a vehicle
// key or replayed is dropped and counted by its reason, and the last genuine one stays.
TEST(CorrectionFilter, FixWithheldNoticeIsKeptOnlyWhenGenuineAndOurs) {
  const v2i::security::SigningKey rsu_key = key_from(1);
  const v2i::security::SigningKey car_key = key_from(3);
  CorrectionFilterConfig config{kFilteredVehicle, 64, {}, {}};
  config.trust_list.add({rsu_key.public_key(), v2i::security::SignerRole::kRsu, {1}});
  config.trust_list.add({car_key.public_key(), v2i::security::SignerRole::kVehicle, {kFilteredVehicle}});
  CorrectionFilter filter(config);
  v2i::MessageSigner rsu(rsu_key);
  v2i::FixWithheld notice;
  notice.rsu_id = 1;
  notice.vehicle_id = kFilteredVehicle;
  notice.sweep_time = kNow - 40 * kNsPerMs;
  notice.reason = v2i::FixWithheldReason::kPositionUnbounded;
  notice.position_sigma_m = 0.73;
  notice.max_position_sigma_m = 0.5;
  v2i::Correction out;
  const std::vector<std::uint8_t> genuine = rsu.encode(notice, kNow);
  EXPECT_EQ(filter.check(genuine, kNow, out), CorrectionVerdict::kFixWithheld);
  EXPECT_EQ(filter.last_fix_withheld().reason, v2i::FixWithheldReason::kPositionUnbounded);
  EXPECT_EQ(filter.last_fix_withheld().position_sigma_m, 0.73);

  v2i::FixWithheld other = notice;
  other.vehicle_id = kFilteredVehicle + 1;
  other.reason = v2i::FixWithheldReason::kNoFit;
  EXPECT_EQ(filter.check(rsu.encode(other, kNow), kNow, out), CorrectionVerdict::kWrongVehicleId);
  v2i::FixWithheld forged = notice;
  forged.reason = v2i::FixWithheldReason::kMount;
  EXPECT_EQ(filter.check(v2i::encode_v2i_message(forged), kNow, out), CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.check(v2i::MessageSigner(key_from(2)).encode(forged, kNow), kNow, out),
            CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.check(v2i::MessageSigner(car_key).encode(forged, kNow), kNow, out),
            CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.check(genuine, kNow + 10, out), CorrectionVerdict::kNotAuthentic);
  EXPECT_EQ(filter.last_fix_withheld().reason, v2i::FixWithheldReason::kPositionUnbounded);

  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kFixWithheld), 1U);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kWrongVehicleId), 1U);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kNotAuthentic), 4U);
  const auto& a = filter.authentication_counts();
  EXPECT_EQ(a.count(v2i::AuthVerdict::kUnsigned), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kUnknownSigner), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kWrongRole), 1U);
  EXPECT_EQ(a.count(v2i::AuthVerdict::kDuplicate), 1U);
}

}  // namespace
}  // namespace rsu::vehicle
