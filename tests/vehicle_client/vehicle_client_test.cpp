// SPDX-License-Identifier: Apache-2.0
// VehicleClient over loopback against a fake RSU (a plain UDP socket): what goes out, what comes back,
// and what is refused.
#include "vehicle_client/vehicle_client.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <variant>

#include "../v2i/test_keys.h"
#include "fake_rsu.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/wire_codec.h"

namespace rsu::vehicle_client {
namespace {

using namespace std::chrono_literals;
namespace asio = boost::asio;

constexpr std::uint64_t kClientVehicleId = 4242;
constexpr TimeNs kClientStart = 1'700'000'000 * kNsPerSecond;

struct ManualClock {
  std::shared_ptr<std::atomic<TimeNs>> now = std::make_shared<std::atomic<TimeNs>>(kClientStart);
  Clock clock() const {
    return [n = now] { return n->load(); };
  }
};

VehicleClientConfig config_for(const test::FakeRsu& rsu) {
  VehicleClientConfig config;
  config.vehicle_id = kClientVehicleId;
  config.size = {4.5, 1.8, 1.5};
  config.reference_offset = {-1.3, 0.0};  // rear axle 1.3 m behind the box centre
  config.rsu_endpoints = {rsu.endpoint_text()};
  config.bind_address = "127.0.0.1";
  config.announce_period = 0;  // no keep-alive unless a test wants it
  // Unsigned: these tests are about the client's mechanics (SignedMode... below covers signatures).
  config.security.mode = v2i::SecurityMode::kInsecure;
  return config;
}

// Runs the io_context in small slices until `done` or the time limit: every wait is bounded.
template <typename Done>
bool run_until(asio::io_context& io, Done done, std::chrono::milliseconds limit = 3000ms) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) {
      return false;
    }
    io.restart();
    io.run_for(5ms);
  }
  return true;
}

VehicleState state_at(int k) {
  VehicleState s;
  s.time = kClientStart + k * 100 * kNsPerMs;
  s.pose = {100.0 + k, -20.0 + 0.5 * k, 0.3 + 0.01 * k};
  s.covariance = Eigen::Vector3d(0.04, 0.05, 0.001).asDiagonal();
  s.speed_mps = 10.0;
  s.yaw_rate_rps = 0.1;
  return s;
}

v2i::VehicleAnnouncement decode_announcement(const std::vector<std::uint8_t>& bytes) {
  const v2i::DecodedMessage decoded = v2i::decode_v2i_message(bytes);
  EXPECT_EQ(decoded.status, v2i::DecodeStatus::kOk);
  const auto* a = std::get_if<v2i::VehicleAnnouncement>(&decoded.body);
  EXPECT_NE(a, nullptr);
  return a ? *a : v2i::VehicleAnnouncement{};
}

v2i::Correction correction(std::uint32_t sequence, TimeNs sweep_time) {
  v2i::Correction c;
  c.rsu_id = 7;
  c.vehicle_id = kClientVehicleId;
  c.sequence = sequence;
  c.sweep_time = sweep_time;
  c.pose = {101.5, -19.0, 0.31};
  c.pose_covariance = Eigen::Vector3d(0.01, 0.01, 0.0004).asDiagonal();
  c.quality.points_used = 321;
  c.quality.faces_seen = 2;
  c.quality.range_m = 17.5;
  c.quality.confidence = 0.9;
  return c;
}

// Announces once and returns what the fake RSU received.
v2i::VehicleAnnouncement announce_once(asio::io_context& io, VehicleClient& client, test::FakeRsu& rsu) {
  EXPECT_EQ(client.announce(state_at(0)), v2i::AnnouncementReason::kValid);
  EXPECT_TRUE(run_until(io, [&] { return client.stats().announcements_sent >= 1; }));
  const auto bytes = rsu.receive();
  EXPECT_TRUE(bytes.has_value());
  return bytes ? decode_announcement(*bytes) : v2i::VehicleAnnouncement{};
}

TEST(VehicleClient, AnnouncementsCarryTheStateAndIncreasingSequences) {
  test::FakeRsu rsu;
  asio::io_context io;
  ManualClock clock;
  VehicleClient client(io, config_for(rsu), clock.clock());
  ASSERT_EQ(client.local_endpoint().address().to_string(), "127.0.0.1");
  ASSERT_NE(client.local_endpoint().port(), 0);

  constexpr int kCount = 5;
  for (int k = 0; k < kCount; ++k) {
    ASSERT_EQ(client.announce(state_at(k)), v2i::AnnouncementReason::kValid);
  }
  ASSERT_TRUE(run_until(io, [&] { return client.stats().announcements_sent == kCount; }));
  for (int k = 0; k < kCount; ++k) {
    const auto bytes = rsu.receive();
    ASSERT_TRUE(bytes.has_value()) << "announcement " << k;
    const v2i::VehicleAnnouncement a = decode_announcement(*bytes);
    const VehicleState expected = state_at(k);
    EXPECT_EQ(a.protocol_version, v2i::kProtocolVersion);
    EXPECT_EQ(a.vehicle_id, kClientVehicleId);
    EXPECT_EQ(a.sequence, static_cast<std::uint32_t>(k));
    EXPECT_EQ(a.generation_time, expected.time);
    EXPECT_DOUBLE_EQ(a.size.length_m, 4.5);
    EXPECT_DOUBLE_EQ(a.size.width_m, 1.8);
    EXPECT_DOUBLE_EQ(a.size.height_m, 1.5);
    EXPECT_DOUBLE_EQ(a.reference_offset.x(), -1.3);
    EXPECT_DOUBLE_EQ(a.reference_offset.y(), 0.0);
    EXPECT_DOUBLE_EQ(a.pose.x, expected.pose.x);
    EXPECT_DOUBLE_EQ(a.pose.y, expected.pose.y);
    EXPECT_DOUBLE_EQ(a.pose.yaw, expected.pose.yaw);
    EXPECT_EQ(a.pose_covariance, expected.covariance);
    ASSERT_TRUE(a.speed_mps && a.yaw_rate_rps);
    EXPECT_DOUBLE_EQ(*a.speed_mps, 10.0);
    EXPECT_DOUBLE_EQ(*a.yaw_rate_rps, 0.1);
    EXPECT_EQ(a.reply_to.address, "127.0.0.1");
    EXPECT_EQ(a.reply_to.port, client.local_endpoint().port());
    // What the client sends passes the RSU's own validation.
    EXPECT_EQ(v2i::validate_announcement(a, expected.time), v2i::AnnouncementReason::kValid);
  }
  EXPECT_EQ(client.next_sequence(), static_cast<std::uint32_t>(kCount));
}

TEST(VehicleClient, UnknownMotionIsAnnouncedAsAbsentAndAnyAddressRepliesFromTheRoutedOne) {
  test::FakeRsu rsu;
  asio::io_context io;
  VehicleClientConfig config = config_for(rsu);
  config.bind_address.clear();  // any address: the reply address comes from the route to the RSU
  VehicleClient client(io, config);
  VehicleState s = state_at(0);
  s.speed_mps.reset();
  s.yaw_rate_rps.reset();
  ASSERT_EQ(client.announce(s), v2i::AnnouncementReason::kValid);
  ASSERT_TRUE(run_until(io, [&] { return client.stats().announcements_sent == 1; }));
  const auto bytes = rsu.receive();
  ASSERT_TRUE(bytes.has_value());
  const v2i::VehicleAnnouncement a = decode_announcement(*bytes);
  EXPECT_FALSE(a.speed_mps.has_value());
  EXPECT_FALSE(a.yaw_rate_rps.has_value());
  EXPECT_EQ(a.reply_to.address, "127.0.0.1");
  EXPECT_EQ(a.reply_to.port, client.local_endpoint().port());
}

TEST(VehicleClient, ImplausibleStatesAreRefusedAndNotSent) {
  test::FakeRsu rsu;
  asio::io_context io;
  VehicleClient client(io, config_for(rsu));
  VehicleState nan_pose = state_at(0);
  nan_pose.pose.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(client.announce(nan_pose), v2i::AnnouncementReason::kNonFinite);
  VehicleState bad_covariance = state_at(0);
  bad_covariance.covariance(0, 0) = -1.0;
  EXPECT_EQ(client.announce(bad_covariance), v2i::AnnouncementReason::kCovarianceInvalid);
  run_until(
      io, [] { return false; }, 100ms);
  EXPECT_FALSE(rsu.receive(2).has_value());
  EXPECT_EQ(client.stats().announcements_refused, 2U);
  EXPECT_EQ(client.stats().announcements_sent, 0U);
  EXPECT_EQ(client.next_sequence(), 0U);  // refused states use no sequence number
}

TEST(VehicleClient, CorrectionsToTheAnnouncedEndpointReachCallbackAndPoll) {
  test::FakeRsu rsu;
  asio::io_context io;
  ManualClock clock;
  VehicleClient client(io, config_for(rsu), clock.clock());
  std::vector<ReceivedCorrection> called;
  client.set_correction_callback([&](const ReceivedCorrection& r) { called.push_back(r); });
  const v2i::VehicleAnnouncement a = announce_once(io, client, rsu);

  clock.now->store(kClientStart + 123);
  constexpr int kCount = 3;
  for (int k = 0; k < kCount; ++k) {
    rsu.send_to(v2i::encode_v2i_message(correction(10 + k, kClientStart + k * 100 * kNsPerMs)),
                a.reply_to.address, a.reply_to.port);
  }
  ASSERT_TRUE(run_until(io, [&] { return called.size() == kCount; }));
  const std::vector<ReceivedCorrection> polled = client.poll();
  ASSERT_EQ(polled.size(), static_cast<std::size_t>(kCount));
  for (int k = 0; k < kCount; ++k) {
    const auto i = static_cast<std::size_t>(k);
    for (const ReceivedCorrection* r :
         std::initializer_list<const ReceivedCorrection*>{&called[i], &polled[i]}) {
      EXPECT_EQ(r->correction.sequence, static_cast<std::uint32_t>(10 + k));
      EXPECT_EQ(r->correction.sweep_time, kClientStart + k * 100 * kNsPerMs);
      EXPECT_EQ(r->correction.rsu_id, 7U);
      EXPECT_DOUBLE_EQ(r->correction.pose.x, 101.5);
      EXPECT_DOUBLE_EQ(r->correction.pose.yaw, 0.31);
      EXPECT_EQ(r->correction.quality.points_used, 321U);
      EXPECT_EQ(r->received_time, kClientStart + 123);  // the injected clock, not the host's
      EXPECT_EQ(r->sender, "127.0.0.1:" + std::to_string(rsu.port()));
    }
  }
  EXPECT_TRUE(client.poll().empty());  // only what arrived since the last call
  EXPECT_EQ(client.stats().accepted(), static_cast<std::uint64_t>(kCount));
  EXPECT_EQ(client.stats().rejected(), 0U);
}

TEST(VehicleClient, BadDatagramsAreCountedByReasonAndDropped) {
  test::FakeRsu rsu;
  asio::io_context io;
  VehicleClient client(io, config_for(rsu));
  const v2i::VehicleAnnouncement a = announce_once(io, client, rsu);
  auto send = [&](const std::vector<std::uint8_t>& bytes) {
    rsu.send_to(bytes, a.reply_to.address, a.reply_to.port);
  };

  const TimeNs t0 = kClientStart;
  send(v2i::encode_v2i_message(correction(1, t0)));  // good
  send({0xde, 0xad, 0xbe, 0xef, 0x01, 0x02, 0x03});  // garbage
  send({});                                          // empty: garbage
  send(std::vector<std::uint8_t>(1500, 0x08));       // oversized: garbage
  send(v2i::encode_v2i_message(a));                  // not a correction
  v2i::Correction other = correction(2, t0 + 100);
  other.vehicle_id = kClientVehicleId + 1;
  send(v2i::encode_v2i_message(other));  // wrong vehicle
  v2i::Correction future_version = correction(2, t0 + 100);
  future_version.protocol_version = v2i::kProtocolVersion + 1;
  send(v2i::encode_v2i_message(future_version));  // unknown version
  v2i::Correction nan = correction(2, t0 + 100);
  nan.pose.y = std::numeric_limits<double>::quiet_NaN();
  send(v2i::encode_v2i_message(nan));                      // invalid content
  send(v2i::encode_v2i_message(correction(1, t0)));        // duplicate of the first
  send(v2i::encode_v2i_message(correction(0, t0 - 100)));  // stale: an older sweep
  send(v2i::encode_v2i_message(correction(2, t0 + 100)));  // good
  constexpr std::uint64_t kSent = 11;

  ASSERT_TRUE(run_until(io, [&] { return client.stats().datagrams_received == kSent; }));
  const VehicleClientStats stats = client.stats();
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kAccepted), 2U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kGarbage), 3U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kNotACorrection), 1U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kWrongVehicleId), 1U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kUnknownVersion), 1U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kInvalidContent), 1U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kDuplicate), 1U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kStale), 1U);
  EXPECT_EQ(stats.rejected(), kSent - 2);
  const auto polled = client.poll();
  ASSERT_EQ(polled.size(), 2U);
  EXPECT_EQ(polled[0].correction.sequence, 1U);
  EXPECT_EQ(polled[1].correction.sequence, 2U);
}

TEST(VehicleClient, KeepAliveRepeatsTheLatestPoseUntilItIsTooOld) {
  test::FakeRsu rsu;
  asio::io_context io;
  ManualClock clock;
  VehicleClientConfig config = config_for(rsu);
  config.announce_period = 20 * kNsPerMs;
  config.max_resend_age = 1 * kNsPerSecond;
  VehicleClient client(io, config, clock.clock());
  const VehicleState s = state_at(0);
  clock.now->store(s.time);
  ASSERT_EQ(client.announce(s), v2i::AnnouncementReason::kValid);
  ASSERT_TRUE(run_until(io, [&] { return client.stats().announcements_sent >= 4; }));
  for (std::uint32_t k = 0; k < 4; ++k) {
    const auto bytes = rsu.receive();
    ASSERT_TRUE(bytes.has_value());
    const v2i::VehicleAnnouncement a = decode_announcement(*bytes);
    EXPECT_EQ(a.sequence, k);              // a fresh sequence each time ...
    EXPECT_EQ(a.generation_time, s.time);  // ... for the same, honestly dated pose
  }
  EXPECT_GE(client.stats().keepalive_announcements, 3U);

  // The pose is now older than max_resend_age on the client's clock: no more repeats.
  clock.now->store(s.time + 2 * kNsPerSecond);
  run_until(
      io, [] { return false; }, 60ms);  // lets an in-flight repeat finish
  const std::uint64_t sent = client.stats().announcements_sent;
  run_until(
      io, [] { return false; }, 150ms);
  EXPECT_EQ(client.stats().announcements_sent, sent);
}

TEST(VehicleClient, ThreadedClientDeliversCorrectionsOnItsOwnThread) {
  test::FakeRsu rsu;
  ThreadedVehicleClient threaded(config_for(rsu));
  VehicleClient& client = threaded.client();
  std::mutex mutex;
  std::condition_variable arrived;
  std::vector<std::uint32_t> sequences;
  client.set_correction_callback([&](const ReceivedCorrection& r) {
    const std::lock_guard lock(mutex);
    sequences.push_back(r.correction.sequence);
    arrived.notify_all();
  });
  ASSERT_EQ(client.announce(state_at(0)), v2i::AnnouncementReason::kValid);
  const auto bytes = rsu.receive();
  ASSERT_TRUE(bytes.has_value());
  const v2i::VehicleAnnouncement a = decode_announcement(*bytes);
  rsu.send_to(v2i::encode_v2i_message(correction(5, kClientStart)), a.reply_to.address, a.reply_to.port);
  std::unique_lock lock(mutex);
  ASSERT_TRUE(arrived.wait_for(lock, 3s, [&] { return !sequences.empty(); }));
  EXPECT_EQ(sequences.front(), 5U);
}

TEST(VehicleClient, NoCallbackAfterStop) {
  test::FakeRsu rsu;
  asio::io_context io;
  VehicleClient client(io, config_for(rsu));
  int calls = 0;
  client.set_correction_callback([&](const ReceivedCorrection&) { ++calls; });
  const v2i::VehicleAnnouncement a = announce_once(io, client, rsu);
  client.stop();
  rsu.send_to(v2i::encode_v2i_message(correction(1, kClientStart)), a.reply_to.address, a.reply_to.port);
  run_until(
      io, [] { return false; }, 100ms);
  EXPECT_EQ(calls, 0);
  EXPECT_TRUE(client.poll().empty());
  EXPECT_EQ(client.announce(state_at(1)), v2i::AnnouncementReason::kValid);  // a no-op, not a crash
}

TEST(VehicleClient, BadConfigIsRefusedWithAReason) {
  asio::io_context io;
  VehicleClientConfig config;
  config.security.mode = v2i::SecurityMode::kInsecure;
  config.vehicle_id = 1;
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);  // no RSU
  config.rsu_endpoints = {"127.0.0.1"};
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);  // no port
  config.rsu_endpoints = {"127.0.0.1:70000"};
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);
  config.rsu_endpoints = {"127.0.0.1:7000", "[::1]:7000"};
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);  // mixed families
  config.rsu_endpoints = {"127.0.0.1:7000"};
  config.bind_address = "not-an-address";
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);
  config.bind_address = "127.0.0.1";
  config.reply_address = "224.0.0.1";  // multicast: corrections cannot be aimed at a group
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);
  config.reply_address.clear();
  config.vehicle_id = 0;
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);
  config.vehicle_id = 1;
  EXPECT_NO_THROW(VehicleClient(io, config));
  config.security.mode = v2i::SecurityMode::kSigned;  // without a key
  EXPECT_THROW(VehicleClient(io, config), std::invalid_argument);
}

// Signed mode over loopback: the RSU can verify the announcements as this vehicle's, and the client
// uses a correction only when the RSU's key signed it, fresh and not replayed.
// An RSU's notices that it withheld this vehicle's fix are counted by reason and the latest kept, with
// who sent it; none is delivered as a correction or counted as a rejected one.
TEST(VehicleClient, FixWithheldNoticesAreCountedByReasonNeverPolled) {
  test::FakeRsu rsu;
  asio::io_context io;
  VehicleClient client(io, config_for(rsu));
  const v2i::VehicleAnnouncement a = announce_once(io, client, rsu);
  auto notice = [&](v2i::FixWithheldReason reason, std::uint64_t vehicle_id) {
    v2i::FixWithheld n;
    n.rsu_id = 7;
    n.vehicle_id = vehicle_id;
    n.announcement_sequence = a.sequence;
    n.sweep_time = kClientStart - 20 * kNsPerMs;
    n.reason = reason;
    rsu.send_to(v2i::encode_v2i_message(n), a.reply_to.address, a.reply_to.port);
  };
  notice(v2i::FixWithheldReason::kPositionUnbounded, kClientVehicleId);
  notice(v2i::FixWithheldReason::kPositionUnbounded, kClientVehicleId);
  notice(v2i::FixWithheldReason::kInconsistent, kClientVehicleId + 1);  // another vehicle's
  notice(v2i::FixWithheldReason::kNoOwnCluster, kClientVehicleId);
  ASSERT_TRUE(run_until(io, [&] { return client.stats().datagrams_received == 4; }));
  const VehicleClientStats stats = client.stats();
  EXPECT_EQ(stats.fixes_withheld.count(v2i::FixWithheldReason::kPositionUnbounded), 2U);
  EXPECT_EQ(stats.fixes_withheld.count(v2i::FixWithheldReason::kNoOwnCluster), 1U);
  EXPECT_EQ(stats.fixes_withheld.count(v2i::FixWithheldReason::kInconsistent), 0U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kFixWithheld), 3U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kWrongVehicleId), 1U);
  EXPECT_EQ(stats.rejected(), 1U);
  ASSERT_TRUE(stats.last_fix_withheld.has_value());
  EXPECT_EQ(stats.last_fix_withheld->notice.reason, v2i::FixWithheldReason::kNoOwnCluster);
  EXPECT_EQ(stats.last_fix_withheld->sender, rsu.endpoint_text());
  EXPECT_TRUE(client.poll().empty());
}

TEST(VehicleClient, SignedModeSignsAnnouncementsAndVerifiesCorrectionsBeforeUse) {
  const v2i::security::SigningKey car = key_from(3);
  const v2i::security::SigningKey rsu_key = key_from(4);
  const v2i::security::SigningKey forger = key_from(5);
  test::FakeRsu rsu;
  asio::io_context io;
  ManualClock clock;
  VehicleClientConfig config = config_for(rsu);
  config.security.mode = v2i::SecurityMode::kSigned;
  config.signing_key = car;
  config.trust_list.add({rsu_key.public_key(), v2i::security::SignerRole::kRsu, {7}});
  VehicleClient client(io, config, clock.clock());

  ASSERT_EQ(client.announce(state_at(0)), v2i::AnnouncementReason::kValid);
  ASSERT_TRUE(run_until(io, [&] { return client.stats().announcements_sent == 1; }));
  const auto sent = rsu.receive();
  ASSERT_TRUE(sent.has_value());
  v2i::security::TrustList rsu_trust;
  rsu_trust.add({car.public_key(), v2i::security::SignerRole::kVehicle, {kClientVehicleId}});
  v2i::MessageAuthenticator at_rsu(v2i::SecurityConfig{}, rsu_trust);
  const v2i::AuthenticatedMessage heard = at_rsu.authenticate(*sent, kClientStart + 5 * kNsPerMs);
  ASSERT_EQ(heard.verdict, v2i::AuthVerdict::kAccepted);
  const auto& a = std::get<v2i::VehicleAnnouncement>(heard.message.body);
  EXPECT_EQ(heard.message.header.generation_time, kClientStart);  // the client's clock when it signed

  v2i::MessageSigner rsu_signer(rsu_key);
  v2i::MessageSigner forged(forger);
  auto send = [&](const std::vector<std::uint8_t>& bytes) {
    rsu.send_to(bytes, a.reply_to.address, a.reply_to.port);
  };
  const std::vector<std::uint8_t> genuine =
      rsu_signer.encode(correction(1, kClientStart - 40 * kNsPerMs), kClientStart);
  send(genuine);
  send(forged.encode(correction(2, kClientStart - 30 * kNsPerMs), kClientStart));  // forged: wrong key
  send(genuine);                                                                   // replayed
  send(v2i::encode_v2i_message(correction(3, kClientStart - 20 * kNsPerMs)));      // unsigned
  send(rsu_signer.encode(correction(4, kClientStart - 10 * kNsPerMs), kClientStart + 10));  // genuine
  ASSERT_TRUE(run_until(io, [&] { return client.stats().datagrams_received == 5; }));
  const VehicleClientStats stats = client.stats();
  EXPECT_EQ(stats.accepted(), 2U);
  EXPECT_EQ(stats.corrections.count(CorrectionVerdict::kNotAuthentic), 3U);
  EXPECT_EQ(stats.authentication.count(v2i::AuthVerdict::kUnknownSigner), 1U);
  EXPECT_EQ(stats.authentication.count(v2i::AuthVerdict::kDuplicate), 1U);
  EXPECT_EQ(stats.authentication.count(v2i::AuthVerdict::kUnsigned), 1U);
  const auto polled = client.poll();
  ASSERT_EQ(polled.size(), 2U);
  EXPECT_EQ(polled[0].correction.sequence, 1U);
  EXPECT_EQ(polled[1].correction.sequence, 4U);
}

}  // namespace
}  // namespace rsu::vehicle_client
