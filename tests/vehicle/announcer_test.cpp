// SPDX-License-Identifier: Apache-2.0
// Announcer: one signed datagram per RSU, each with that RSU's reply address and the same announcement
// sequence; implausible states refused without a sequence spent; the keep-alive decision against the
// test's own clock arithmetic.
#include "vehicle/announcer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <variant>

#include "../v2i/test_keys.h"
#include "v2i/message_authenticator.h"
#include "v2i/wire_codec.h"

namespace rsu::vehicle {
namespace {

constexpr std::uint64_t kVehicleId = 31;
constexpr TimeNs kStart = 1'700'000'000 * kNsPerSecond;

AnnouncerConfig config() {
  AnnouncerConfig c;
  c.vehicle_id = kVehicleId;
  c.size = {4.5, 1.8, 1.5};
  c.reference_offset = {-1.3, 0.0};
  c.announce_period = 100 * kNsPerMs;
  c.max_resend_age = 1 * kNsPerSecond;
  return c;
}

VehicleState state_at(TimeNs t) {
  VehicleState s;
  s.time = t;
  s.pose = {12.0, -3.0, 0.4};
  s.covariance = Eigen::Vector3d(0.04, 0.05, 0.001).asDiagonal();
  s.speed_mps = 9.0;
  return s;
}

const std::vector<v2i::UdpEndpoint> kReplyTo = {{"127.0.0.1", 40001}, {"10.0.0.7", 40001}};

TEST(Announcer, OneSignedDatagramPerRsuWithItsOwnReplyAddress) {
  const v2i::security::SigningKey car = key_from(9);
  Announcer announcer(config(), car);
  v2i::security::TrustList trust;
  trust.add({car.public_key(), v2i::security::SignerRole::kVehicle, {kVehicleId}});
  v2i::MessageAuthenticator rsu(v2i::SecurityConfig{}, trust);
  for (std::uint32_t k = 0; k < 3; ++k) {
    std::vector<std::vector<std::uint8_t>> out;
    const TimeNs now = kStart + k * 100 * kNsPerMs;
    ASSERT_EQ(announcer.announce(state_at(now - 5 * kNsPerMs), now, kReplyTo, out),
              v2i::AnnouncementReason::kValid);
    ASSERT_EQ(out.size(), kReplyTo.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      const v2i::AuthenticatedMessage heard = rsu.authenticate(out[i], now);
      ASSERT_EQ(heard.verdict, v2i::AuthVerdict::kAccepted) << v2i::to_string(heard.verdict);
      const auto& a = std::get<v2i::VehicleAnnouncement>(heard.message.body);
      EXPECT_EQ(a.sequence, k);                             // one announcement sequence for all RSUs ...
      EXPECT_EQ(heard.message.header.sequence, 2 * k + i);  // ... and the signer's own per datagram
      EXPECT_EQ(heard.message.header.generation_time, now);
      EXPECT_EQ(a.generation_time, now - 5 * kNsPerMs);  // the pose's own time
      EXPECT_EQ(a.reply_to.address, kReplyTo[i].address);
      EXPECT_EQ(a.reply_to.port, kReplyTo[i].port);
      EXPECT_EQ(a.vehicle_id, kVehicleId);
      EXPECT_DOUBLE_EQ(a.size.length_m, 4.5);
      EXPECT_DOUBLE_EQ(a.reference_offset.x(), -1.3);
      EXPECT_DOUBLE_EQ(a.pose.yaw, 0.4);
      ASSERT_TRUE(a.speed_mps.has_value());
      EXPECT_DOUBLE_EQ(*a.speed_mps, 9.0);
      EXPECT_FALSE(a.yaw_rate_rps.has_value());
    }
  }
  EXPECT_EQ(announcer.next_sequence(), 3U);
}

TEST(Announcer, WithoutAKeyTheDatagramsAreUnsigned) {
  Announcer announcer(config(), std::nullopt);
  std::vector<std::vector<std::uint8_t>> out;
  ASSERT_EQ(announcer.announce(state_at(kStart), kStart, kReplyTo, out), v2i::AnnouncementReason::kValid);
  ASSERT_EQ(out.size(), 2U);
  const v2i::DecodedEnvelope envelope = v2i::decode_envelope(out[0]);
  ASSERT_EQ(envelope.status, v2i::DecodeStatus::kOk);
  EXPECT_TRUE(envelope.envelope.signature.empty());
}

TEST(Announcer, AnImplausibleStateIsRefusedAndSpendsNoSequence) {
  Announcer announcer(config(), key_from(9));
  VehicleState bad = state_at(kStart);
  bad.pose.x = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::vector<std::uint8_t>> out = {{1, 2, 3}};
  EXPECT_NE(announcer.announce(bad, kStart, kReplyTo, out), v2i::AnnouncementReason::kValid);
  EXPECT_EQ(out.size(), 1U);  // untouched
  EXPECT_EQ(announcer.next_sequence(), 0U);
  // Nor is it kept for the keep-alive.
  EXPECT_FALSE(announcer.keepalive_due(1 * kNsPerSecond, kStart).has_value());
  bad.covariance(0, 1) = 5.0;  // not symmetric
  bad.pose.x = 1.0;
  EXPECT_NE(announcer.announce(bad, kStart, kReplyTo, out), v2i::AnnouncementReason::kValid);
}

TEST(Announcer, KeepAliveRepeatsTheLatestPoseWhileTheRsuWouldTakeIt) {
  Announcer announcer(config(), std::nullopt);
  EXPECT_FALSE(announcer.keepalive_due(10 * kNsPerSecond, kStart).has_value());  // nothing announced yet
  std::vector<std::vector<std::uint8_t>> out;
  const VehicleState s = state_at(kStart);
  ASSERT_EQ(announcer.announce(s, kStart, kReplyTo, out), v2i::AnnouncementReason::kValid);
  const TimeNs period = config().announce_period;
  EXPECT_FALSE(announcer.keepalive_due(period - 1, kStart + period).has_value());  // not quiet long enough
  const auto due = announcer.keepalive_due(period, kStart + period);
  ASSERT_TRUE(due.has_value());
  EXPECT_EQ(due->time, s.time);  // the same, honestly dated pose
  EXPECT_DOUBLE_EQ(due->pose.x, s.pose.x);
  EXPECT_TRUE(announcer.keepalive_due(period, kStart + config().max_resend_age).has_value());
  EXPECT_FALSE(announcer.keepalive_due(period, kStart + config().max_resend_age + 1).has_value());

  AnnouncerConfig off = config();
  off.announce_period = 0;
  Announcer never(off, std::nullopt);
  ASSERT_EQ(never.announce(s, kStart, kReplyTo, out), v2i::AnnouncementReason::kValid);
  EXPECT_FALSE(never.keepalive_due(10 * kNsPerSecond, kStart + period).has_value());
}

}  // namespace
}  // namespace rsu::vehicle
