// SPDX-License-Identifier: Apache-2.0
// RsuCore in signed mode: announcements are taken only from trusted vehicle keys for their own ids,
// fresh and not replayed (also when a peer RSU relays the vehicle's original bytes); the corrections and
// advertisements it sends verify with its key at a vehicle; a reload keeps the replay state.
#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "../v2i/test_keys.h"
#include "core/rsu_core.h"
#include "sim_stream.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/wire_codec.h"

namespace rsu::core {
namespace {

using testing::announce;
using testing::SimStream;
using testing::static_vehicle;

constexpr TimeNs kNow = 5 * kNsPerSecond;
constexpr std::uint64_t kRsuId = 77;

struct Keys {
  v2i::security::SigningKey rsu = key_from(1);
  v2i::security::SigningKey car1 = key_from(2);  // vehicle 1
  v2i::security::SigningKey car2 = key_from(3);  // vehicle 2
  v2i::security::SigningKey stranger = key_from(4);

  // What an RSU trusts: the vehicles, each for its id, and the RSUs (a list shared by a deployment).
  v2i::security::TrustList vehicles() const {
    v2i::security::TrustList list;
    list.add({car1.public_key(), v2i::security::SignerRole::kVehicle, {1}});
    list.add({car2.public_key(), v2i::security::SignerRole::kVehicle, {2}});
    list.add({rsu.public_key(), v2i::security::SignerRole::kRsu, {kRsuId}});
    return list;
  }
  // What a vehicle trusts: this RSU's key, for its id.
  v2i::security::TrustList rsus() const {
    v2i::security::TrustList list;
    list.add({rsu.public_key(), v2i::security::SignerRole::kRsu, {kRsuId}});
    return list;
  }
};

RsuCoreConfig signed_config(const Keys& keys) {
  RsuCoreConfig c;
  c.rsu_id = kRsuId;
  c.sensor_model = "vlp16";
  c.mount = testing::roadside_mount();
  c.background.learning_frames = 3;
  c.signing_key = keys.rsu;
  c.trust_list = keys.vehicles();
  return c;
}

SourceEndpoint from(const std::string& address) {
  return {address, 40000};
}

TEST(RsuCoreSecurity, SignedModeNeedsAKey) {
  Keys keys;
  RsuCoreConfig c = signed_config(keys);
  c.signing_key.reset();
  EXPECT_THROW(RsuCore{c}, std::invalid_argument);
}

TEST(RsuCoreSecurity, OnlyGenuineFreshAnnouncementsAreRegistered) {
  Keys keys;
  RsuCore core(signed_config(keys));
  v2i::MessageSigner car1(keys.car1);
  v2i::MessageSigner car2(keys.car2);
  v2i::MessageSigner stranger(keys.stranger);
  const std::string host = "192.0.2.10";
  const auto a1 = announce(1, 1, kNow, {10.0, 2.0, 0.5}, host);
  const std::vector<std::uint8_t> genuine = car1.encode(a1, kNow);
  EXPECT_EQ(core.on_datagram(genuine, from(host), kNow).reason(), "accepted:added");

  struct Case {
    const char* what;
    std::vector<std::uint8_t> bytes;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"replayed", genuine, "auth:duplicate"},
      {"unsigned", v2i::encode_v2i_message(announce(1, 2, kNow, {10.0, 2.0, 0.5}, host)), "auth:unsigned"},
      {"unknown key", stranger.encode(announce(1, 3, kNow, {10.0, 2.0, 0.5}, host), kNow),
       "auth:unknown_signer"},
      {"car 2's key for car 1", car2.encode(announce(1, 4, kNow, {10.0, 2.0, 0.5}, host), kNow),
       "auth:wrong_subject"},
      {"stale", car1.encode(announce(1, 5, kNow, {10.0, 2.0, 0.5}, host), kNow - 2 * kNsPerSecond),
       "auth:stale"},
      {"RSU's own key",
       v2i::MessageSigner(keys.rsu).encode(announce(1, 6, kNow, {10.0, 2.0, 0.5}, host), kNow),
       "auth:wrong_role"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(core.on_datagram(c.bytes, from(host), kNow + 1).reason(), c.expected) << c.what;
  }
  // The genuine flow goes on, and car 2 speaks for itself.
  EXPECT_EQ(core.on_datagram(car1.encode(announce(1, 7, kNow, {10.0, 2.0, 0.5}, host), kNow + 2), from(host),
                             kNow + 3)
                .reason(),
            "accepted:updated");
  EXPECT_TRUE(
      core.on_datagram(car2.encode(announce(2, 1, kNow, {20.0, 2.0, 0.5}, host), kNow), from(host), kNow + 3)
          .accepted());
  EXPECT_EQ(core.registry().size(), 2U);
  EXPECT_EQ(core.datagram_stages().count(DatagramStage::kAuthentication), cases.size());
  bool listed = false;
  for (const auto& [name, value] : core.counters()) {
    if (name == "auth.duplicate") {
      listed = true;
      EXPECT_EQ(value, 1U);
    }
    if (name == "security.insecure_mode") {
      EXPECT_EQ(value, 0U);
    }
  }
  EXPECT_TRUE(listed);
}

// A peer RSU shares the vehicle's original datagram (over DDS, RsuCore::on_peer_announcement): it
// verifies there as the vehicle's own; a copy heard directly as well is a duplicate; tampered or
// unsigned shared datagrams are refused.
TEST(RsuCoreSecurity, SharedOriginalBytesVerifyAtThePeer) {
  Keys keys;
  RsuCore peer(signed_config(keys));
  v2i::MessageSigner car1(keys.car1);
  const std::string host = "192.0.2.10";
  const PeerProvenance shared{.origin_rsu_id = kRsuId + 1, .sender = {host, 40000}};
  const std::vector<std::uint8_t> original = car1.encode(announce(1, 1, kNow, {10.0, 2.0, 0.5}, host), kNow);
  EXPECT_EQ(peer.on_peer_announcement(original, shared, kNow + 2 * kNsPerMs).reason(), "accepted:added");
  EXPECT_EQ(peer.on_datagram(original, from(host), kNow + 3 * kNsPerMs).reason(), "auth:duplicate");
  // The other way round (heard directly first, then shared by the peer): not news, not an auth failure.
  const std::vector<std::uint8_t> heard_first =
      car1.encode(announce(1, 4, kNow, {10.0, 2.0, 0.5}, host), kNow);
  EXPECT_TRUE(peer.on_datagram(heard_first, from(host), kNow + 3 * kNsPerMs).accepted());
  EXPECT_EQ(peer.on_peer_announcement(heard_first, shared, kNow + 4 * kNsPerMs).reason(), "not_fresher");
  // Tampered on the way: the vehicle's signature no longer holds.
  std::vector<std::uint8_t> tampered = car1.encode(announce(1, 2, kNow, {10.0, 2.0, 0.5}, host), kNow);
  tampered[tampered.size() / 2] ^= 0x01;
  const std::string r = peer.on_peer_announcement(tampered, shared, kNow + 4 * kNsPerMs).reason();
  EXPECT_TRUE(r == "auth:bad_signature" || r.starts_with("decode:")) << r;
  EXPECT_EQ(peer.on_peer_announcement(v2i::encode_v2i_message(announce(1, 3, kNow, {10.0, 2.0, 0.5}, host)),
                                      shared, kNow + 5 * kNsPerMs)
                .reason(),
            "auth:unsigned");
  EXPECT_EQ(peer.peer_stages().count(DatagramStage::kAuthentication), 2U);
}

TEST(RsuCoreSecurity, CorrectionsAndAdvertisementsVerifyAtTheVehicle) {
  Keys keys;
  const Pose2 truth{17.0, 2.0, 0.4};
  constexpr int kEmptyRotations = 5;
  SimStream stream({static_vehicle(1, truth)}, kEmptyRotations);
  RsuCore core(signed_config(keys));
  v2i::MessageSigner car1(keys.car1);
  const TimeNs t1 = kEmptyRotations * stream.rotation_ns();
  std::uint32_t seq = 1;
  for (TimeNs t = t1 - 200 * kNsPerMs; t <= t1; t += 100 * kNsPerMs) {
    const auto a = announce(1, seq++, t, {truth.x + 0.3, truth.y - 0.2, truth.yaw}, "192.0.2.10");
    ASSERT_TRUE(core.on_datagram(car1.encode(a, t), from("192.0.2.10"), t).accepted());
  }
  stream.run_until(core, t1 + 3 * stream.rotation_ns());
  ASSERT_GE(stream.corrections().size(), 2U);

  v2i::MessageAuthenticator vehicle(v2i::SecurityConfig{}, keys.rsus());
  for (const auto& [out, emitted_at] : stream.corrections()) {
    const v2i::AuthenticatedMessage m = vehicle.authenticate(out.bytes, emitted_at);
    ASSERT_EQ(m.verdict, v2i::AuthVerdict::kAccepted);
    EXPECT_EQ(std::get<v2i::Correction>(m.message.body).sweep_time, out.correction.sweep_time);
    EXPECT_EQ(m.message.header.generation_time, emitted_at);  // signed when sent
  }
  // The same bytes again are refused.
  const auto& [first, first_at] = stream.corrections().front();
  EXPECT_EQ(vehicle.authenticate(first.bytes, first_at + 1).verdict, v2i::AuthVerdict::kDuplicate);
  const TimeNs later = t1 + 4 * stream.rotation_ns();
  EXPECT_EQ(vehicle.authenticate(core.advertisement(later), later).verdict, v2i::AuthVerdict::kAccepted);
}

// A genuine announcement refused after authentication (here: reply_to on another port than the one it
// came from) gets a signed refusal notice that verifies at the vehicle with the RSU's key and says why;
// nothing refused before authentication gets one (a forged source cannot aim notices at a third party).
TEST(RsuCoreSecurity, RefusalNoticesOnlyForAuthenticatedAnnouncementsAndSigned) {
  Keys keys;
  RsuCore core(signed_config(keys));
  v2i::MessageSigner car1(keys.car1);
  v2i::MessageSigner stranger(keys.stranger);
  const std::string host = "192.0.2.10";
  auto other_port = announce(1, 1, kNow, {10.0, 2.0, 0.5}, host);
  other_port.reply_to.port = testing::kVehiclePort + 1;
  const DatagramOutcome refused = core.on_datagram(car1.encode(other_port, kNow), from(host), kNow);
  EXPECT_EQ(refused.reason(), "reply_to_mismatch:port");
  ASSERT_FALSE(refused.refusal_notice.empty());

  v2i::MessageAuthenticator vehicle(v2i::SecurityConfig{}, keys.rsus());
  const v2i::AuthenticatedMessage m = vehicle.authenticate(refused.refusal_notice, kNow);
  ASSERT_EQ(m.verdict, v2i::AuthVerdict::kAccepted);
  const auto& notice = std::get<v2i::AnnouncementRefusal>(m.message.body);
  EXPECT_EQ(notice.rsu_id, kRsuId);
  EXPECT_EQ(notice.vehicle_id, 1U);
  EXPECT_EQ(notice.announcement_sequence, 1U);
  EXPECT_EQ(notice.reason, v2i::RefusalReason::kReplyToMismatch);
  EXPECT_EQ(notice.detail, "port");

  // Refused before authentication, a second later (past the per-vehicle interval): no notice.
  const TimeNs later = kNow + 2 * kNsPerSecond;
  const auto a = announce(1, 2, later, {10.0, 2.0, 0.5}, host);
  for (const auto& bytes :
       {v2i::encode_v2i_message(a), stranger.encode(a, later), car1.encode(a, later - 3 * kNsPerSecond)}) {
    const DatagramOutcome out = core.on_datagram(bytes, from(host), later);
    EXPECT_EQ(out.stage, DatagramStage::kAuthentication) << out.reason();
    EXPECT_TRUE(out.refusal_notice.empty()) << out.reason();
  }
}

TEST(RsuCoreSecurity, ReloadKeepsReplayStateAndAppliesTheNewTrustList) {
  Keys keys;
  RsuCoreConfig config = signed_config(keys);
  RsuCore core(config);
  v2i::MessageSigner car1(keys.car1);
  const auto bytes = car1.encode(announce(1, 1, kNow, {10.0, 2.0, 0.5}, "192.0.2.10"), kNow);
  ASSERT_TRUE(core.on_datagram(bytes, from("192.0.2.10"), kNow).accepted());
  RsuCoreConfig revoked = config;
  revoked.trust_list = v2i::security::TrustList();
  core.reload(revoked, kNow + 1);
  EXPECT_EQ(core.on_datagram(car1.encode(announce(1, 2, kNow, {10.0, 2.0, 0.5}, "192.0.2.10"), kNow + 1),
                             from("192.0.2.10"), kNow + 2)
                .reason(),
            "auth:unknown_signer");
  core.reload(config, kNow + 3);
  EXPECT_EQ(core.on_datagram(bytes, from("192.0.2.10"), kNow + 4).reason(), "auth:duplicate");  // remembered
}

// Verify on demand (RsuCoreConfig::verify_beyond_coverage_m): a vehicle in radio range but out of
// sight is neither verified nor registered, and is the moment it claims a place within coverage + margin
// (of the LiDAR's position, not the map's origin); a peer's share of it likewise; a reload applies a new
// margin, and "all" (none) verifies everything again.
TEST(RsuCoreSecurity, AnnouncementsBeyondCoveragePlusMarginAreNeitherVerifiedNorRegistered) {
  Keys keys;
  RsuCoreConfig config = signed_config(keys);
  config.coverage_radius_m = 50.0;
  config.verify_beyond_coverage_m = 30.0;  // 80 m from the LiDAR at (2, -3)
  RsuCore core(config);
  v2i::MessageSigner car1(keys.car1);
  const std::string host = "192.0.2.10";
  const auto signed_at = [&](std::uint32_t seq, double x, double y) {
    return car1.encode(announce(1, seq, kNow, {x, y, 0.0}, host), kNow);
  };
  const auto verified = [&] {
    for (const auto& [name, value] : core.counters())
      if (name == "auth.signatures_verified")
        return value;
    ADD_FAILURE() << "auth.signatures_verified not listed";
    return std::uint64_t{0};
  };
  // Driving in along y = -3 from 200 m: dropped unverified until 80 m from the LiDAR.
  std::uint32_t seq = 1;
  for (double x = 202.0; x > 82.5; x -= 10.0)
    EXPECT_EQ(core.on_datagram(signed_at(seq++, x, -3.0), from(host), kNow).reason(),
              "beyond_verification_radius")
        << x;
  EXPECT_EQ(verified(), 0U);
  EXPECT_EQ(core.registry().size(), 0U);
  // 79.9 m from the LiDAR (but 80.0 m from the map's origin): verified and registered.
  EXPECT_EQ(core.on_datagram(signed_at(seq++, 81.9, -3.0), from(host), kNow + 1).reason(), "accepted:added");
  EXPECT_EQ(verified(), 1U);
  // A forgery claiming a far place for car 1 changes nothing, and costs no verification.
  std::vector<std::uint8_t> forged = signed_at(seq, 300.0, -3.0);
  forged[forged.size() - 5] ^= 0x01;  // in the signature, the envelope's last field
  EXPECT_EQ(core.on_datagram(forged, from(host), kNow + 2).reason(), "beyond_verification_radius");
  EXPECT_EQ(verified(), 1U);
  EXPECT_EQ(core.on_datagram(signed_at(seq++, 70.0, -3.0), from(host), kNow + 3).reason(),
            "accepted:updated");
  EXPECT_EQ(core.registry().find(1, kNow + 3)->announcement.pose.x, 70.0);
  // A peer's share of car 2 out of sight: not registered; within the radius: registered.
  const PeerProvenance shared{.origin_rsu_id = kRsuId + 1, .sender = {"192.0.2.20", 40000}};
  v2i::MessageSigner car2(keys.car2);
  EXPECT_EQ(core.on_peer_announcement(car2.encode(announce(2, 1, kNow, {2.0, 90.0, 0.0}, "192.0.2.20"), kNow),
                                      shared, kNow + 4)
                .reason(),
            "beyond_verification_radius");
  EXPECT_EQ(core.on_peer_announcement(car2.encode(announce(2, 2, kNow, {2.0, 70.0, 0.0}, "192.0.2.20"), kNow),
                                      shared, kNow + 5)
                .reason(),
            "accepted:added");
  EXPECT_EQ(core.datagram_stages().count(DatagramStage::kBeyondVerification), 13U);
  EXPECT_EQ(core.peer_stages().count(DatagramStage::kBeyondVerification), 1U);
  bool listed = false;
  for (const auto& [name, value] : core.counters()) {
    if (name == "datagram.beyond_verification_radius") {
      listed = true;
      EXPECT_EQ(value, 13U);
    }
  }
  EXPECT_TRUE(listed);
  // Reloaded with every announcement verified: the far one is verified (and accepted).
  config.verify_beyond_coverage_m.reset();
  core.reload(config, kNow + 6);
  EXPECT_EQ(core.on_datagram(signed_at(seq++, 300.0, -3.0), from(host), kNow + 7).reason(),
            "accepted:updated");
  EXPECT_EQ(verified(), 4U);
}

TEST(RsuCoreSecurity, InsecureModeSendsUnsignedAndSaysSo) {
  Keys keys;
  RsuCoreConfig c = signed_config(keys);
  c.security.mode = v2i::SecurityMode::kInsecure;
  RsuCore core(c);
  const auto ad = v2i::decode_envelope(core.advertisement(kNow));
  ASSERT_EQ(ad.status, v2i::DecodeStatus::kOk);
  EXPECT_TRUE(ad.envelope.signature.empty());
  EXPECT_TRUE(core.on_datagram(v2i::encode_v2i_message(announce(1, 1, kNow, {10.0, 2.0, 0.5}, "192.0.2.10")),
                               from("192.0.2.10"), kNow)
                  .accepted());
  for (const auto& [name, value] : core.counters()) {
    if (name == "security.insecure_mode" || name == "auth.accepted_unverified") {
      EXPECT_EQ(value, 1U) << name;
    }
  }
}

}  // namespace
}  // namespace rsu::core
