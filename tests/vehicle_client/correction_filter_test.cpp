// CorrectionFilter: ordering per RSU, restart of an RSU, sequence wrap-around and bounded memory.
#include "vehicle_client/correction_filter.h"

#include <gtest/gtest.h>

#include "v2i/wire_codec.h"

namespace rsu::vehicle_client {
namespace {

constexpr std::uint64_t kVehicleId = 99;

std::vector<std::uint8_t> datagram(std::uint64_t rsu_id, std::uint32_t sequence, TimeNs sweep_time) {
  v2i::Correction c;
  c.rsu_id = rsu_id;
  c.vehicle_id = kVehicleId;
  c.sequence = sequence;
  c.sweep_time = sweep_time;
  c.pose = {1.0, 2.0, 0.5};
  c.pose_covariance = Eigen::Matrix3d::Identity() * 0.01;
  return v2i::encode_v2i_message(c);
}

TEST(CorrectionFilter, OrderIsKeptPerRsu) {
  CorrectionFilter filter({kVehicleId, 64});
  v2i::Correction out;
  EXPECT_EQ(filter.check(datagram(1, 10, 1000), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(out.sequence, 10U);
  // Another RSU has its own counter and clock of sweeps: an earlier sweep from it is news.
  EXPECT_EQ(filter.check(datagram(2, 3, 500), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 10, 1000), out), CorrectionVerdict::kDuplicate);
  EXPECT_EQ(filter.check(datagram(1, 9, 900), out), CorrectionVerdict::kStale);
  EXPECT_EQ(filter.check(datagram(1, 11, 1100), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.counts().count(CorrectionVerdict::kAccepted), 3U);
  EXPECT_EQ(filter.counts().total(), 5U);
  EXPECT_EQ(filter.sequence_restarts(), 0U);
}

TEST(CorrectionFilter, ARestartedRsuIsHeardAgain) {
  CorrectionFilter filter({kVehicleId, 64});
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 500, 5000), out), CorrectionVerdict::kAccepted);
  // The daemon restarted: its counter begins again, its sweeps are later.
  EXPECT_EQ(filter.check(datagram(1, 0, 9000), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 1, 9100), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.sequence_restarts(), 1U);
}

TEST(CorrectionFilter, SequenceWrapAroundIsNotARestart) {
  CorrectionFilter filter({kVehicleId, 64});
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 0xFFFFFFFFU, 100), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.check(datagram(1, 0, 200), out), CorrectionVerdict::kAccepted);
  EXPECT_EQ(filter.sequence_restarts(), 0U);
}

TEST(CorrectionFilter, ForgetsTheLeastRecentlyHeardRsuBeyondItsCapacity) {
  CorrectionFilter filter({kVehicleId, 2});
  v2i::Correction out;
  ASSERT_EQ(filter.check(datagram(1, 1, 100), out), CorrectionVerdict::kAccepted);
  ASSERT_EQ(filter.check(datagram(2, 1, 100), out), CorrectionVerdict::kAccepted);
  ASSERT_EQ(filter.check(datagram(3, 1, 100), out), CorrectionVerdict::kAccepted);  // RSU 1 forgotten
  // RSU 1's duplicate is no longer recognised (memory stays bounded) ...
  EXPECT_EQ(filter.check(datagram(1, 1, 100), out), CorrectionVerdict::kAccepted);
  // ... which evicted RSU 2, while RSU 3 is still remembered.
  EXPECT_EQ(filter.check(datagram(3, 1, 100), out), CorrectionVerdict::kDuplicate);
}

TEST(CorrectionFilter, TruncatedBytesAreGarbage) {
  CorrectionFilter filter({kVehicleId, 64});
  v2i::Correction out;
  const std::vector<std::uint8_t> whole = datagram(1, 1, 100);
  ASSERT_GT(whole.size(), 10U);
  // The correction is one length-delimited field of the envelope: every strict prefix either cuts it
  // (a parse error) or leaves it out (no body), so every one is garbage.
  for (std::size_t n = 0; n < whole.size(); ++n) {
    EXPECT_EQ(filter.check({whole.data(), n}, out), CorrectionVerdict::kGarbage) << n << " bytes";
  }
  EXPECT_EQ(filter.check(whole, out), CorrectionVerdict::kAccepted);
}

}  // namespace
}  // namespace rsu::vehicle_client
