// SPDX-License-Identifier: Apache-2.0
// rsu-relay's faults (CorrectionTamper): corrections altered as configured and signed again so that the
// vehicle's authenticator accepts them; everything else passes untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <variant>

#include "../v2i/test_keys.h"
#include "tools/rsu_relay/correction_tamper.h"
#include "v2i/message_authenticator.h"
#include "v2i/wire_codec.h"

namespace rsu::tools {
namespace {

constexpr TimeNs kStart = 1'700'000'000 * kNsPerSecond;

v2i::Correction correction_at(TimeNs sweep, std::uint32_t sequence) {
  v2i::Correction c;
  c.rsu_id = 1;
  c.vehicle_id = 5;
  c.sequence = sequence;
  c.sweep_time = sweep;
  c.pose = {10.0, -2.0, 0.1};
  c.pose_covariance = Eigen::Vector3d(0.0025, 0.0036, 0.0004).asDiagonal();
  return c;
}

struct Vehicle {
  v2i::security::SigningKey rsu = key_from(21);
  v2i::MessageAuthenticator authenticator;
  Vehicle() : authenticator(v2i::SecurityConfig{}, trust()) {}
  v2i::security::TrustList trust() const {
    v2i::security::TrustList list;
    list.add({rsu.public_key(), v2i::security::SignerRole::kRsu, {1}});
    return list;
  }
  // The correction as the vehicle would accept it, or nothing.
  std::optional<v2i::Correction> accept(const std::vector<std::uint8_t>& bytes, TimeNs now) {
    const v2i::AuthenticatedMessage m = authenticator.authenticate(bytes, now);
    if (m.verdict != v2i::AuthVerdict::kAccepted) {
      return std::nullopt;
    }
    return std::get<v2i::Correction>(m.message.body);
  }
};

TEST(CorrectionTamper, BiasAndCovarianceFromTheStartTimeSignedAgainWithTheRsuKey) {
  Vehicle vehicle;
  TamperConfig config;
  config.bias_m = {0.3, -1.0};
  config.covariance_scale = 0.04;
  config.from = kStart + 1 * kNsPerSecond;
  CorrectionTamper tamper(config, vehicle.rsu);
  v2i::MessageSigner rsud(vehicle.rsu, 500);  // rsud's own signer sequence
  for (int k = 0; k < 20; ++k) {
    const TimeNs sweep = kStart + k * 100 * kNsPerMs;
    const v2i::Correction original = correction_at(sweep, static_cast<std::uint32_t>(k));
    const TamperedDatagram out = tamper.process(rsud.encode(original, sweep + 5 * kNsPerMs));
    const auto seen = vehicle.accept(out.bytes, sweep + 10 * kNsPerMs);
    ASSERT_TRUE(seen.has_value()) << k;  // re-signed: genuine, fresh, not a replay
    const bool after = sweep >= config.from;
    EXPECT_EQ(out.altered, after);
    EXPECT_NEAR(seen->pose.x, original.pose.x + (after ? 0.3 : 0.0), 1e-12);
    EXPECT_NEAR(seen->pose.y, original.pose.y + (after ? -1.0 : 0.0), 1e-12);
    EXPECT_NEAR(seen->pose_covariance(1, 1), original.pose_covariance(1, 1) * (after ? 0.04 : 1.0), 1e-15);
    EXPECT_EQ(seen->sequence, original.sequence);  // the RSU's per-vehicle sequence is kept
  }
}

TEST(CorrectionTamper, WrongVehicleBurstsFollowTheirPeriod) {
  Vehicle vehicle;
  TamperConfig config;
  config.burst_offset_m = {6.0, 3.5};
  config.burst_period = 2 * kNsPerSecond;
  config.burst_length = 300 * kNsPerMs;
  config.from = kStart;
  CorrectionTamper tamper(config, vehicle.rsu);
  v2i::MessageSigner rsud(vehicle.rsu);
  int bursts = 0;
  for (int k = 0; k < 60; ++k) {
    const TimeNs sweep = kStart + k * 100 * kNsPerMs;
    const TamperedDatagram out = tamper.process(rsud.encode(correction_at(sweep, 0), sweep));
    const bool expected = (k % 20) < 3;  // 0.3 s of every 2 s
    EXPECT_EQ(out.burst, expected) << k;
    bursts += out.burst ? 1 : 0;
    const auto seen = vehicle.accept(out.bytes, sweep);
    ASSERT_TRUE(seen.has_value());
    EXPECT_DOUBLE_EQ(seen->pose.x, 10.0 + (expected ? 6.0 : 0.0));
  }
  EXPECT_EQ(bursts, 9);
}

TEST(CorrectionTamper, WithoutFaultsOrForOtherMessagesTheBytesPassUntouched) {
  Vehicle vehicle;
  v2i::MessageSigner rsud(vehicle.rsu);
  const std::vector<std::uint8_t> bytes = rsud.encode(correction_at(kStart, 1), kStart);
  CorrectionTamper none(TamperConfig{}, vehicle.rsu);
  const TamperedDatagram plain = none.process(bytes);
  EXPECT_EQ(plain.bytes, bytes);
  EXPECT_FALSE(plain.altered);
  ASSERT_TRUE(plain.correction.has_value());

  TamperConfig biased;
  biased.bias_m = {1.0, 0.0};
  CorrectionTamper tamper(biased, vehicle.rsu);
  v2i::VehicleAnnouncement announcement;
  announcement.vehicle_id = 5;
  const std::vector<std::uint8_t> other = v2i::encode_v2i_message(announcement);
  EXPECT_EQ(tamper.process(other).bytes, other);
  const std::vector<std::uint8_t> garbage = {1, 2, 3};
  EXPECT_EQ(tamper.process(garbage).bytes, garbage);
  EXPECT_FALSE(tamper.process(garbage).correction.has_value());
}

}  // namespace
}  // namespace rsu::tools
