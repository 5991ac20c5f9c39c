// SPDX-License-Identifier: Apache-2.0
// The receiving side of message security: every verdict, on datagrams the test builds and signs
// itself, and the counts.
#include "v2i/message_authenticator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "proto/v2i.pb.h"
#include "test_announcement.h"
#include "test_keys.h"
#include "v2i/message_signer.h"

namespace rsu::v2i {
namespace {

using security::SigningKey;

constexpr TimeNs kAuthNow = 1'700'000'000 * kNsPerSecond;
constexpr std::uint64_t kVehicle = 7;
constexpr std::uint64_t kRsu = 1;

struct Keys {
  SigningKey rsu = key_from(1);
  SigningKey car = key_from(2);
  SigningKey stranger = key_from(3);

  security::TrustList trust() const {
    security::TrustList list;
    list.add({rsu.public_key(), security::SignerRole::kRsu, {kRsu}});
    list.add({car.public_key(), security::SignerRole::kVehicle, {kVehicle}});
    return list;
  }
};

Correction correction_from(std::uint64_t rsu_id) {
  Correction c;
  c.rsu_id = rsu_id;
  c.vehicle_id = kVehicle;
  c.sweep_time = kAuthNow - 50 * kNsPerMs;
  return c;
}

// Re-wraps a datagram's envelope after `change` edited it (tampering on the wire).
template <typename Change>
std::vector<std::uint8_t> tamper(const std::vector<std::uint8_t>& bytes, Change change) {
  v2::SignedV2iMessage m;
  EXPECT_TRUE(m.ParseFromArray(bytes.data(), static_cast<int>(bytes.size())));
  change(m);
  std::string out;
  EXPECT_TRUE(m.SerializeToString(&out));
  return {out.begin(), out.end()};
}

class MessageAuthenticatorTest : public ::testing::Test {
 protected:
  AuthVerdict verdict(const std::vector<std::uint8_t>& bytes, TimeNs now = kAuthNow) {
    return auth_.authenticate(bytes, now).verdict;
  }
  std::vector<std::uint8_t> announcement(const SigningKey* key, std::uint32_t seq, TimeNs t = kAuthNow,
                                         std::uint64_t vehicle = kVehicle) {
    return encode_v2i_message(testing::make_announcement(vehicle, seq, t), {t, seq}, key);
  }

  Keys keys_;
  MessageAuthenticator auth_{SecurityConfig{}, keys_.trust()};
};

TEST_F(MessageAuthenticatorTest, GenuineMessagesAreAcceptedWithTheirContent) {
  const AuthenticatedMessage a = auth_.authenticate(announcement(&keys_.car, 10), kAuthNow);
  ASSERT_EQ(a.verdict, AuthVerdict::kAccepted);
  EXPECT_TRUE(a.accepted());
  EXPECT_EQ(a.signer, keys_.car.key_id());
  EXPECT_EQ(a.message.header.sequence, 10U);
  EXPECT_EQ(std::get<VehicleAnnouncement>(a.message.body).vehicle_id, kVehicle);
  MessageSigner rsu(keys_.rsu);
  EXPECT_EQ(verdict(rsu.encode(correction_from(kRsu), kAuthNow)), AuthVerdict::kAccepted);
  RsuAdvertisement ad;
  ad.rsu_id = kRsu;
  EXPECT_EQ(verdict(rsu.encode(ad, kAuthNow)), AuthVerdict::kAccepted);
}

TEST_F(MessageAuthenticatorTest, EveryRefusalHasItsReason) {
  const std::vector<std::uint8_t> good = announcement(&keys_.car, 10);
  struct RefusalCase {
    const char* what;
    std::vector<std::uint8_t> bytes;
    AuthVerdict expected;
  };
  const std::vector<RefusalCase> cases = {
      {"garbage", {0xFF, 0xFF}, AuthVerdict::kMalformed},
      {"version 1", {0x08, 0x01, 0x12, 0x02, 0x08, 0x07}, AuthVerdict::kMalformed},
      {"unsigned", announcement(nullptr, 11), AuthVerdict::kUnsigned},
      {"short key id", tamper(good, [](auto& m) { m.mutable_signer_key_id()->pop_back(); }),
       AuthVerdict::kMalformedSignature},
      {"signature only", tamper(good, [](auto& m) { m.clear_signer_key_id(); }),
       AuthVerdict::kMalformedSignature},
      {"short signature", tamper(good, [](auto& m) { m.mutable_signature()->pop_back(); }),
       AuthVerdict::kMalformedSignature},
      {"unknown signer", announcement(&keys_.stranger, 12), AuthVerdict::kUnknownSigner},
      {"payload tampered", tamper(good, [](auto& m) { m.mutable_payload()->back() ^= 1; }),
       AuthVerdict::kBadSignature},
      {"signature tampered", tamper(good, [](auto& m) { m.mutable_signature()->front() ^= 1; }),
       AuthVerdict::kBadSignature},
      // The car's signature presented as the RSU's: key ids select the key, the signature still fails.
      {"key id swapped",
       tamper(good,
              [&](auto& m) { m.set_signer_key_id(keys_.rsu.key_id().data(), keys_.rsu.key_id().size()); }),
       AuthVerdict::kBadSignature},
      {"RSU key announcing", announcement(&keys_.rsu, 13), AuthVerdict::kWrongRole},
      {"vehicle key correcting", encode_v2i_message(correction_from(kRsu), {kAuthNow, 14}, &keys_.car),
       AuthVerdict::kWrongRole},
      {"another vehicle's id", announcement(&keys_.car, 15, kAuthNow, kVehicle + 1),
       AuthVerdict::kWrongSubject},
      {"another RSU's id", encode_v2i_message(correction_from(kRsu + 1), {kAuthNow, 16}, &keys_.rsu),
       AuthVerdict::kWrongSubject},
      {"stale", announcement(&keys_.car, 17, kAuthNow - 1001 * kNsPerMs), AuthVerdict::kStale},
      {"future", announcement(&keys_.car, 18, kAuthNow + 1001 * kNsPerMs), AuthVerdict::kFuture},
  };
  for (const RefusalCase& c : cases) {
    EXPECT_EQ(verdict(c.bytes), c.expected) << c.what;
  }
  // None of the refusals above touched the car's window: the genuine message is still fresh, once.
  EXPECT_EQ(verdict(good), AuthVerdict::kAccepted);
  EXPECT_EQ(verdict(good), AuthVerdict::kDuplicate);
  for (std::uint32_t s = 11; s < 11 + 64; ++s)
    ASSERT_EQ(verdict(announcement(&keys_.car, s + 100)), AuthVerdict::kAccepted);
  EXPECT_EQ(verdict(announcement(&keys_.car, 11)), AuthVerdict::kTooOld);

  const EnumCounter<AuthVerdict>& n = auth_.counts();
  EXPECT_EQ(n.count(AuthVerdict::kMalformed), 2U);
  EXPECT_EQ(n.count(AuthVerdict::kMalformedSignature), 3U);
  EXPECT_EQ(n.count(AuthVerdict::kBadSignature), 3U);
  EXPECT_EQ(n.count(AuthVerdict::kWrongRole), 2U);
  EXPECT_EQ(n.count(AuthVerdict::kWrongSubject), 2U);
  EXPECT_EQ(n.count(AuthVerdict::kAccepted), 65U);
  EXPECT_EQ(n.count(AuthVerdict::kDuplicate), 1U);
  EXPECT_EQ(n.count(AuthVerdict::kTooOld), 1U);
  EXPECT_EQ(n.total(), cases.size() + 67U);
}

// Verifying costs ~40 us: what the time or sequence window refuses anyway is refused before it (a receiver
// behind with a backlog would otherwise spend its time verifying what it then refuses as stale), and such a
// check records nothing, so a forgery cannot move a signer's window.
TEST_F(MessageAuthenticatorTest, WindowRefusalsComeBeforeTheSignature) {
  const auto forge = [](const std::vector<std::uint8_t>& bytes) {
    return tamper(bytes, [](auto& m) { m.mutable_signature()->front() ^= 1; });
  };
  const std::vector<std::uint8_t> good = announcement(&keys_.car, 20);
  ASSERT_EQ(verdict(good), AuthVerdict::kAccepted);
  EXPECT_EQ(auth_.signatures_verified(), 1U);
  EXPECT_EQ(verdict(forge(announcement(&keys_.car, 21, kAuthNow - 1001 * kNsPerMs))), AuthVerdict::kStale);
  EXPECT_EQ(verdict(forge(announcement(&keys_.car, 22, kAuthNow + 1001 * kNsPerMs))), AuthVerdict::kFuture);
  EXPECT_EQ(verdict(forge(good)), AuthVerdict::kDuplicate);
  EXPECT_EQ(verdict(good), AuthVerdict::kDuplicate);
  EXPECT_EQ(auth_.signatures_verified(), 1U);  // none of these four was verified
  EXPECT_EQ(auth_.refused_before_signature(), 4U);
  // A forgery the windows let through is verified and refused, and leaves the window as it was: the
  // genuine message with that number is still fresh, once.
  EXPECT_EQ(verdict(forge(announcement(&keys_.car, 23))), AuthVerdict::kBadSignature);
  EXPECT_EQ(auth_.signatures_verified(), 2U);
  EXPECT_EQ(verdict(announcement(&keys_.car, 23)), AuthVerdict::kAccepted);  // verified: 3
  EXPECT_EQ(verdict(announcement(&keys_.car, 23)), AuthVerdict::kDuplicate);
  EXPECT_EQ(auth_.refused_before_signature(), 5U);
  // Checked ahead (rsud's receiver thread) within the receiver's time window: a stale or future message
  // is not verified there either, and authenticate() refuses it by its time.
  const TimeWindow window{kAuthNow, 1000 * kNsPerMs, 1000 * kNsPerMs};
  const std::vector<std::uint8_t> stale = announcement(&keys_.car, 30, kAuthNow - 1001 * kNsPerMs);
  const std::vector<std::uint8_t> future = announcement(&keys_.car, 31, kAuthNow + 1001 * kNsPerMs);
  const std::vector<std::uint8_t> fresh = announcement(&keys_.car, 32, kAuthNow - 999 * kNsPerMs);
  EXPECT_FALSE(check_signature_ahead(stale, keys_.trust(), window));
  EXPECT_FALSE(check_signature_ahead(future, keys_.trust(), window));
  EXPECT_TRUE(check_signature_ahead(stale, keys_.trust()));  // no window: checked
  const auto fresh_check = check_signature_ahead(fresh, keys_.trust(), window);
  ASSERT_TRUE(fresh_check);
  EXPECT_TRUE(fresh_check->valid);
  EXPECT_EQ(auth_.authenticate(stale, kAuthNow, nullptr).verdict, AuthVerdict::kStale);
  EXPECT_EQ(auth_.authenticate(fresh, kAuthNow, &*fresh_check).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(auth_.signatures_verified(), 3U);  // as before this block: the fresh one was checked ahead
  EXPECT_EQ(auth_.signatures_checked_ahead(), 1U);
}

// Verify on demand (VerificationRadius): an announcement claiming a place beyond the radius is dropped
// unverified, whatever its signature, and leaves no trace; within it, or with a pose that is not finite,
// or any other message, is verified as before.
TEST(VerificationRadius, AnAnnouncementBeyondItIsDroppedUnverifiedAndLeavesNoTrace) {
  const Keys keys;
  const VerificationRadius radius{.x = 10.0, .y = -5.0, .radius_m = 100.0};
  MessageAuthenticator auth({.mode = SecurityMode::kSigned, .replay = {}, .verify_within = radius},
                            keys.trust());
  const auto at = [&](double x, double y, std::uint32_t seq, const SigningKey* key) {
    VehicleAnnouncement a = testing::make_announcement(kVehicle, seq, kAuthNow);
    a.pose.x = x;
    a.pose.y = y;
    return encode_v2i_message(a, {kAuthNow, seq}, key);
  };
  const auto forge = [](const std::vector<std::uint8_t>& bytes) {
    return tamper(bytes, [](auto& m) { m.mutable_signature()->front() ^= 1; });
  };
  // Distances from (10, -5): 100.0 exactly (kept), 100.01 and 250 (dropped), in every direction.
  for (int k = 0; k < 8; ++k) {
    const double a = k * 0.785398;
    const auto s = static_cast<std::uint32_t>(100 + 10 * k);
    EXPECT_EQ(auth.authenticate(forge(at(10 + 100.01 * std::cos(a), -5 + 100.01 * std::sin(a), s, &keys.car)),
                                kAuthNow)
                  .verdict,
              AuthVerdict::kNotNeeded)
        << k;
    EXPECT_EQ(
        auth.authenticate(at(10 + 250 * std::cos(a), -5 + 250 * std::sin(a), s + 1, &keys.car), kAuthNow)
            .verdict,
        AuthVerdict::kNotNeeded)
        << k;
    EXPECT_EQ(
        auth.authenticate(forge(at(10 + 99.99 * std::cos(a), -5 + 99.99 * std::sin(a), s + 2, &keys.car)),
                          kAuthNow)
            .verdict,
        AuthVerdict::kBadSignature)
        << k;
  }
  EXPECT_EQ(auth.signatures_verified(), 8U);  // only the eight within the radius
  EXPECT_EQ(auth.counts().count(AuthVerdict::kNotNeeded), 16U);
  // Nothing was recorded: the genuine announcements with the dropped sequence numbers are fresh, once.
  EXPECT_EQ(auth.authenticate(at(10, -5, 100, &keys.car), kAuthNow).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(auth.authenticate(at(10, -5, 101, &keys.car), kAuthNow).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(auth.authenticate(at(10, -5, 101, &keys.car), kAuthNow).verdict, AuthVerdict::kDuplicate);
  // A pose that is not finite is verified (validation refuses it later, by its reason).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(auth.authenticate(forge(at(nan, 0, 200, &keys.car)), kAuthNow).verdict,
            AuthVerdict::kBadSignature);
  EXPECT_EQ(auth.authenticate(forge(at(inf, 0, 201, &keys.car)), kAuthNow).verdict,
            AuthVerdict::kBadSignature);
  EXPECT_EQ(auth.authenticate(forge(at(0, -inf, 202, &keys.car)), kAuthNow).verdict,
            AuthVerdict::kBadSignature);
  // Unsigned, unknown signers and the windows refuse first, by their own reasons.
  EXPECT_EQ(auth.authenticate(at(500, 0, 300, nullptr), kAuthNow).verdict, AuthVerdict::kUnsigned);
  EXPECT_EQ(auth.authenticate(at(500, 0, 301, &keys.stranger), kAuthNow).verdict,
            AuthVerdict::kUnknownSigner);
  EXPECT_EQ(auth.authenticate(at(500, 0, 101, &keys.car), kAuthNow).verdict, AuthVerdict::kDuplicate);
  // Other messages are verified wherever they say anything is.
  MessageSigner rsu(keys.rsu);
  Correction far = correction_from(kRsu);
  far.pose = {900.0, 900.0, 0.0};
  EXPECT_EQ(auth.authenticate(forge(rsu.encode(far, kAuthNow)), kAuthNow).verdict,
            AuthVerdict::kBadSignature);
  // Checked ahead (rsud's receiver thread): not verified there either.
  const TimeWindow window{kAuthNow, 1000 * kNsPerMs, 1000 * kNsPerMs};
  EXPECT_FALSE(check_signature_ahead(at(10, 96, 400, &keys.car), keys.trust(), window, radius));
  const auto near = check_signature_ahead(at(10, 94, 401, &keys.car), keys.trust(), window, radius);
  ASSERT_TRUE(near);
  EXPECT_TRUE(near->valid);
  EXPECT_TRUE(check_signature_ahead(at(10, 96, 402, &keys.car), keys.trust(), window));  // no radius
  // Without a radius (the library's default) everything is verified.
  MessageAuthenticator everything(SecurityConfig{}, keys.trust());
  EXPECT_EQ(everything.authenticate(forge(at(10, 5000, 500, &keys.car)), kAuthNow).verdict,
            AuthVerdict::kBadSignature);
  EXPECT_EQ(everything.counts().count(AuthVerdict::kNotNeeded), 0U);
}

TEST_F(MessageAuthenticatorTest, SignedGarbageIsMalformedNotAccepted) {
  std::string payload = "\xFF\xFF\xFF";
  v2::SignedV2iMessage m;
  m.set_protocol_version(kProtocolVersion);
  m.set_payload(payload);
  const security::Signature sig = keys_.car.sign(signing_input(payload));
  m.set_signer_key_id(keys_.car.key_id().data(), keys_.car.key_id().size());
  m.set_signature(sig.data(), sig.size());
  std::string bytes;
  ASSERT_TRUE(m.SerializeToString(&bytes));
  const AuthenticatedMessage a =
      auth_.authenticate(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), kAuthNow);
  EXPECT_EQ(a.verdict, AuthVerdict::kMalformed);
  EXPECT_EQ(a.message.status, DecodeStatus::kParseError);
}

// A signature without the domain-separation prefix (the bare payload signed) does not verify.
TEST_F(MessageAuthenticatorTest, SignaturesWithoutTheContextDoNotVerify) {
  const std::vector<std::uint8_t> good = announcement(&keys_.car, 1);
  const std::vector<std::uint8_t> bare = tamper(good, [&](auto& m) {
    const std::string& p = m.payload();
    const security::Signature sig =
        keys_.car.sign(std::span(reinterpret_cast<const std::uint8_t*>(p.data()), p.size()));
    m.set_signature(sig.data(), sig.size());
  });
  EXPECT_EQ(verdict(bare), AuthVerdict::kBadSignature);
}

// A peer RSU relays a vehicle's original bytes: they verify as the vehicle's, and a copy heard both
// directly and relayed is taken once.
TEST_F(MessageAuthenticatorTest, ForwardedOriginalBytesVerifyOnce) {
  const std::vector<std::uint8_t> sent = announcement(&keys_.car, 5);
  const std::vector<std::uint8_t> relayed(sent.begin(), sent.end());
  MessageAuthenticator peer(SecurityConfig{}, keys_.trust());
  EXPECT_EQ(peer.authenticate(relayed, kAuthNow + 3 * kNsPerMs).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(peer.authenticate(sent, kAuthNow + 4 * kNsPerMs).verdict, AuthVerdict::kDuplicate);
}

TEST_F(MessageAuthenticatorTest, InsecureModeTakesWellFormedMessagesUnchecked) {
  MessageAuthenticator insecure(
      SecurityConfig{.mode = SecurityMode::kInsecure, .replay = {}, .verify_within = {}}, {});
  const std::vector<std::uint8_t> unsigned_bytes = announcement(nullptr, 1, kAuthNow - 60 * kNsPerSecond);
  EXPECT_EQ(insecure.authenticate(unsigned_bytes, kAuthNow).verdict, AuthVerdict::kAcceptedUnverified);
  EXPECT_EQ(insecure.authenticate(unsigned_bytes, kAuthNow).verdict, AuthVerdict::kAcceptedUnverified);
  EXPECT_EQ(insecure.authenticate(announcement(&keys_.stranger, 1), kAuthNow).verdict,
            AuthVerdict::kAcceptedUnverified);
  EXPECT_EQ(insecure.authenticate(std::vector<std::uint8_t>{0xFF}, kAuthNow).verdict,
            AuthVerdict::kMalformed);
  EXPECT_EQ(insecure.counts().count(AuthVerdict::kAcceptedUnverified), 3U);
}

TEST_F(MessageAuthenticatorTest, ReconfigureKeepsReplayStateAndAppliesTheNewList) {
  const std::vector<std::uint8_t> first = announcement(&keys_.car, 1);
  EXPECT_EQ(verdict(first), AuthVerdict::kAccepted);
  security::TrustList only_rsu;
  only_rsu.add({keys_.rsu.public_key(), security::SignerRole::kRsu, {kRsu}});
  auth_.reconfigure(SecurityConfig{}, only_rsu);
  EXPECT_EQ(verdict(announcement(&keys_.car, 2)), AuthVerdict::kUnknownSigner);  // revoked
  auth_.reconfigure(SecurityConfig{}, keys_.trust());
  EXPECT_EQ(verdict(first), AuthVerdict::kDuplicate);  // still remembered
}

// The signature checked ahead (rsud's receiver thread) gives the verdicts checking it inline gives, and
// is taken only while it was checked against the signer's current key.
TEST_F(MessageAuthenticatorTest, SignaturesCheckedAheadGiveTheSameVerdicts) {
  const security::TrustList trust = keys_.trust();
  const std::vector<std::uint8_t> good = announcement(&keys_.car, 1);
  const std::vector<std::uint8_t> forged = tamper(announcement(&keys_.car, 2), [](auto& m) {
    std::string p = m.payload();
    p.back() = static_cast<char>(p.back() ^ 1);
    m.set_payload(p);
  });
  const auto good_check = check_signature_ahead(good, trust);
  const auto forged_check = check_signature_ahead(forged, trust);
  ASSERT_TRUE(good_check && forged_check);
  EXPECT_TRUE(good_check->valid);
  EXPECT_FALSE(forged_check->valid);
  EXPECT_EQ(good_check->public_key, keys_.car.public_key());
  // Nothing to check ahead: unsigned, signer not listed, not an envelope.
  EXPECT_FALSE(check_signature_ahead(announcement(nullptr, 3), trust));
  EXPECT_FALSE(check_signature_ahead(announcement(&keys_.stranger, 3), trust));
  EXPECT_FALSE(check_signature_ahead(std::vector<std::uint8_t>{0xFF, 0x01}, trust));

  EXPECT_EQ(auth_.authenticate(good, kAuthNow, &*good_check).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(auth_.authenticate(forged, kAuthNow, &*forged_check).verdict, AuthVerdict::kBadSignature);
  EXPECT_EQ(auth_.signatures_checked_ahead(), 2U);
  EXPECT_EQ(auth_.signatures_verified(), 0U);
  // A check that claims validity for bytes it was not made on is not believed against another key:
  // a result checked against a key no longer the signer's (a reloaded list) is verified again.
  SignatureCheck against_old_key = *forged_check;
  against_old_key.public_key = keys_.stranger.public_key();
  against_old_key.valid = true;
  EXPECT_EQ(auth_.authenticate(forged, kAuthNow, &against_old_key).verdict, AuthVerdict::kBadSignature);
  EXPECT_EQ(auth_.signatures_verified(), 1U);
  // The same bytes checked inline by a fresh receiver: the same verdicts.
  MessageAuthenticator inline_auth(SecurityConfig{}, keys_.trust());
  EXPECT_EQ(inline_auth.authenticate(good, kAuthNow).verdict, AuthVerdict::kAccepted);
  EXPECT_EQ(inline_auth.authenticate(forged, kAuthNow).verdict, AuthVerdict::kBadSignature);
  EXPECT_EQ(inline_auth.signatures_verified(), 2U);
}

TEST(MessageSigner, CountsItsSequenceAndStampsTheTime) {
  MessageSigner signer(key_from(4), 0xFFFFFFFFU);
  const DecodedMessage a = decode_v2i_message(signer.encode(correction_from(kRsu), kAuthNow));
  const DecodedMessage b = decode_v2i_message(signer.encode(correction_from(kRsu), kAuthNow + 1));
  EXPECT_EQ(a.header.sequence, 0xFFFFFFFFU);
  EXPECT_EQ(b.header.sequence, 0U);
  EXPECT_EQ(b.header.generation_time, kAuthNow + 1);
  EXPECT_TRUE(signer.signs());
  MessageSigner unsigned_signer(std::nullopt);
  EXPECT_FALSE(unsigned_signer.signs());
  EXPECT_TRUE(
      decode_envelope(unsigned_signer.encode(correction_from(kRsu), kAuthNow)).envelope.signature.empty());
}

}  // namespace
}  // namespace rsu::v2i
