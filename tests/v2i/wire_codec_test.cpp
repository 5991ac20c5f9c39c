// SPDX-License-Identifier: Apache-2.0
#include "v2i/wire_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "common/random.h"
#include "proto/v2i.pb.h"
#include "test_announcement.h"
#include "v2i/announcement_validation.h"

namespace rsu::v2i {
namespace {

constexpr TimeNs kCodecNow = 1'700'000'000 * kNsPerSecond;

std::vector<std::uint8_t> serialise(const v2::SignedV2iMessage& m) {
  std::string s;
  EXPECT_TRUE(m.SerializeToString(&s));
  return {s.begin(), s.end()};
}

// An unsigned version-2 datagram around a hand-built payload.
std::vector<std::uint8_t> wrap(const v2::V2iPayload& payload) {
  v2::SignedV2iMessage m;
  m.set_protocol_version(kProtocolVersion);
  EXPECT_TRUE(payload.SerializeToString(m.mutable_payload()));
  return serialise(m);
}

TEST(WireCodec, AnnouncementRoundTripKeepsEveryField) {
  const VehicleAnnouncement in = testing::make_announcement(0x1234567890ULL, 4'000'000'000U, kCodecNow - 123);
  const std::vector<std::uint8_t> bytes = encode_v2i_message(in);
  ASSERT_FALSE(bytes.empty());
  EXPECT_LE(bytes.size(), kMaxDatagramBytes);
  const DecodedMessage out = decode_v2i_message(bytes);
  ASSERT_EQ(out.status, DecodeStatus::kOk);
  const auto* a = std::get_if<VehicleAnnouncement>(&out.body);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->protocol_version, kProtocolVersion);
  EXPECT_EQ(a->vehicle_id, in.vehicle_id);
  EXPECT_EQ(a->sequence, in.sequence);
  EXPECT_EQ(a->generation_time, in.generation_time);
  EXPECT_EQ(a->size.length_m, in.size.length_m);
  EXPECT_EQ(a->size.width_m, in.size.width_m);
  EXPECT_EQ(a->size.height_m, in.size.height_m);
  EXPECT_EQ(a->reference_offset, in.reference_offset);
  EXPECT_EQ(a->pose.x, in.pose.x);
  EXPECT_EQ(a->pose.y, in.pose.y);
  EXPECT_EQ(a->pose.yaw, in.pose.yaw);
  EXPECT_EQ(a->pose_covariance, in.pose_covariance);
  ASSERT_TRUE(a->speed_mps.has_value());
  EXPECT_EQ(*a->speed_mps, *in.speed_mps);
  ASSERT_TRUE(a->yaw_rate_rps.has_value());
  EXPECT_EQ(*a->yaw_rate_rps, *in.yaw_rate_rps);
  EXPECT_EQ(a->reply_to.address, in.reply_to.address);
  EXPECT_EQ(a->reply_to.port, in.reply_to.port);
}

TEST(WireCodec, AbsentMotionStaysAbsentAndZeroStaysPresent) {
  VehicleAnnouncement in = testing::make_announcement(3, 1, kCodecNow);
  in.speed_mps.reset();
  in.yaw_rate_rps = 0.0;  // known to be zero: must not turn into "unknown"
  const DecodedMessage out = decode_v2i_message(encode_v2i_message(in));
  ASSERT_EQ(out.status, DecodeStatus::kOk);
  const auto& a = std::get<VehicleAnnouncement>(out.body);
  EXPECT_FALSE(a.speed_mps.has_value());
  ASSERT_TRUE(a.yaw_rate_rps.has_value());
  EXPECT_EQ(*a.yaw_rate_rps, 0.0);
}

TEST(WireCodec, CorrectionRoundTrip) {
  Correction in;
  in.rsu_id = 42;
  in.vehicle_id = 7;
  in.sequence = 99;
  in.sweep_time = kCodecNow + 5'000'123;
  in.pose = {10.25, -4.5, -2.9};
  in.pose_covariance << 0.0025, 0.0001, 0.0, 0.0001, 0.003, 0.0, 0.0, 0.0, 0.0004;
  in.quality = {312, 2, 17.5, YawResolution::kPrior, 0.87};
  in.announcement_sequence = 1234;
  const DecodedMessage out = decode_v2i_message(encode_v2i_message(in));
  ASSERT_EQ(out.status, DecodeStatus::kOk);
  const auto& c = std::get<Correction>(out.body);
  EXPECT_EQ(c.rsu_id, 42U);
  EXPECT_EQ(c.vehicle_id, 7U);
  EXPECT_EQ(c.sequence, 99U);
  EXPECT_EQ(c.sweep_time, in.sweep_time);
  EXPECT_EQ(c.pose.x, 10.25);
  EXPECT_EQ(c.pose.y, -4.5);
  EXPECT_EQ(c.pose.yaw, -2.9);
  EXPECT_EQ(c.pose_covariance, in.pose_covariance);
  EXPECT_EQ(c.quality.points_used, 312U);
  EXPECT_EQ(c.quality.faces_seen, 2U);
  EXPECT_EQ(c.quality.range_m, 17.5);
  EXPECT_EQ(c.quality.yaw_resolution, YawResolution::kPrior);
  EXPECT_EQ(c.quality.confidence, 0.87);
  EXPECT_EQ(c.announcement_sequence, 1234U);
}

TEST(WireCodec, AdvertisementRoundTrip) {
  RsuAdvertisement in;
  in.rsu_id = 5;
  in.lidar_pose = {1.5, 2.5, 2.0, 0.01, -0.02, 1.2};
  in.coverage_radius_m = 40.0;
  in.correction_port = 47100;
  in.announcement_port = 47000;
  const DecodedMessage out = decode_v2i_message(encode_v2i_message(in));
  ASSERT_EQ(out.status, DecodeStatus::kOk);
  const auto& r = std::get<RsuAdvertisement>(out.body);
  EXPECT_EQ(r.rsu_id, 5U);
  EXPECT_EQ(r.lidar_pose.x, 1.5);
  EXPECT_EQ(r.lidar_pose.y, 2.5);
  EXPECT_EQ(r.lidar_pose.z, 2.0);
  EXPECT_EQ(r.lidar_pose.roll, 0.01);
  EXPECT_EQ(r.lidar_pose.pitch, -0.02);
  EXPECT_EQ(r.lidar_pose.yaw, 1.2);
  EXPECT_EQ(r.coverage_radius_m, 40.0);
  EXPECT_EQ(r.correction_port, 47100U);
  EXPECT_EQ(r.announcement_port, 47000U);
  EXPECT_EQ(r.fixes_withheld, FixesWithheld::kNone);  // an RSU that says nothing withholds nothing
  EXPECT_EQ(r.mount_error_at_radius_m, 0.0);
}

// Whether the RSU withholds its fixes, and why (added within version 2): kept; a value this code does
// not know reads as withheld for an unknown reason, never as serving.
TEST(WireCodec, AdvertisementSaysWhyFixesAreWithheld) {
  RsuAdvertisement in;
  in.rsu_id = 5;
  in.fixes_withheld = FixesWithheld::kMountSuspected;
  in.mount_error_at_radius_m = 0.107;
  const DecodedMessage out = decode_v2i_message(encode_v2i_message(in));
  ASSERT_EQ(out.status, DecodeStatus::kOk);
  const auto& r = std::get<RsuAdvertisement>(out.body);
  EXPECT_EQ(r.fixes_withheld, FixesWithheld::kMountSuspected);
  EXPECT_EQ(r.mount_error_at_radius_m, 0.107);

  v2::V2iPayload p;
  p.mutable_advertisement()->set_rsu_id(5);
  p.mutable_advertisement()->set_fixes_withheld(static_cast<v2::FixesWithheld>(17));
  const DecodedMessage unknown = decode_v2i_message(wrap(p));
  ASSERT_EQ(unknown.status, DecodeStatus::kOk);
  EXPECT_EQ(std::get<RsuAdvertisement>(unknown.body).fixes_withheld, FixesWithheld::kUnknown);
}

// A refusal notice keeps its fields; a detail the vehicle could not print safely (over 32 bytes, or not
// printable ASCII) makes the datagram unreadable, and a reason this code does not know is unspecified.
TEST(WireCodec, RefusalRoundTripAndItsDetailChecked) {
  AnnouncementRefusal r;
  r.rsu_id = 3;
  r.vehicle_id = 7;
  r.announcement_sequence = 41;
  r.reason = RefusalReason::kReplyToMismatch;
  r.detail = "port";
  const DecodedMessage m = decode_v2i_message(encode_v2i_message(r));
  ASSERT_EQ(m.status, DecodeStatus::kOk);
  const auto& back = std::get<AnnouncementRefusal>(m.body);
  EXPECT_EQ(back.rsu_id, 3U);
  EXPECT_EQ(back.vehicle_id, 7U);
  EXPECT_EQ(back.announcement_sequence, 41U);
  EXPECT_EQ(back.reason, RefusalReason::kReplyToMismatch);
  EXPECT_EQ(back.detail, "port");

  const auto with_detail = [](const std::string& detail, int reason) {
    v2::V2iPayload p;
    p.mutable_refusal()->set_vehicle_id(7);
    p.mutable_refusal()->set_reason(static_cast<v2::RefusalReason>(reason));
    p.mutable_refusal()->set_detail(detail);
    return decode_v2i_message(wrap(p));
  };
  EXPECT_EQ(with_detail(std::string(32, 'a'), 1).status, DecodeStatus::kOk);
  EXPECT_EQ(with_detail(std::string(33, 'a'), 1).status, DecodeStatus::kParseError);
  EXPECT_EQ(with_detail("port\n", 1).status, DecodeStatus::kParseError);
  EXPECT_EQ(with_detail(std::string("p\0rt", 4), 1).status, DecodeStatus::kParseError);
  const DecodedMessage unknown = with_detail("x", 9);
  ASSERT_EQ(unknown.status, DecodeStatus::kOk);
  EXPECT_EQ(std::get<AnnouncementRefusal>(unknown.body).reason, RefusalReason::kUnspecified);
}

FixWithheld withheld_notice() {
  FixWithheld n;
  n.rsu_id = 3;
  n.vehicle_id = 7;
  n.announcement_sequence = 4'000'000'001U;
  n.sweep_time = kCodecNow - 37;
  n.reason = FixWithheldReason::kPositionUnbounded;
  n.position_sigma_m = 0.731;
  n.max_position_sigma_m = 0.1;
  n.packets_lost_nearby = true;
  return n;
}

// A withheld-fix notice keeps every field; absent sigmas stay absent, a zero one present.
TEST(WireCodec, FixWithheldRoundTripKeepsEveryField) {
  const DecodedMessage m = decode_v2i_message(encode_v2i_message(withheld_notice()));
  ASSERT_EQ(m.status, DecodeStatus::kOk);
  const auto& back = std::get<FixWithheld>(m.body);
  EXPECT_EQ(back.rsu_id, 3U);
  EXPECT_EQ(back.vehicle_id, 7U);
  EXPECT_EQ(back.announcement_sequence, 4'000'000'001U);
  EXPECT_EQ(back.sweep_time, kCodecNow - 37);
  EXPECT_EQ(back.reason, FixWithheldReason::kPositionUnbounded);
  EXPECT_EQ(back.position_sigma_m, 0.731);
  EXPECT_EQ(back.max_position_sigma_m, 0.1);
  EXPECT_TRUE(back.packets_lost_nearby);
  EXPECT_EQ(back.mount_cause, FixesWithheld::kNone);

  FixWithheld mount = withheld_notice();
  mount.reason = FixWithheldReason::kMount;
  mount.mount_cause = FixesWithheld::kMountSuspected;
  mount.position_sigma_m.reset();
  mount.max_position_sigma_m = 0.0;
  mount.packets_lost_nearby = false;
  const DecodedMessage m2 = decode_v2i_message(encode_v2i_message(mount));
  ASSERT_EQ(m2.status, DecodeStatus::kOk);
  const auto& back2 = std::get<FixWithheld>(m2.body);
  EXPECT_EQ(back2.reason, FixWithheldReason::kMount);
  EXPECT_EQ(back2.mount_cause, FixesWithheld::kMountSuspected);
  EXPECT_FALSE(back2.position_sigma_m.has_value());
  EXPECT_EQ(back2.max_position_sigma_m, 0.0);
  EXPECT_FALSE(back2.packets_lost_nearby);
}

// A reason or mount cause this code does not know (a newer RSU's) reads as unspecified / unknown, never
// as another; a sigma that is no length (NaN, infinite, negative) makes the notice unreadable.
TEST(WireCodec, FixWithheldUnknownValuesAndBadSigmas) {
  v2::V2iPayload p;
  p.mutable_fix_withheld()->set_vehicle_id(7);
  p.mutable_fix_withheld()->set_reason(static_cast<v2::FixWithheldReason>(42));
  p.mutable_fix_withheld()->set_mount_cause(static_cast<v2::FixesWithheld>(17));
  const DecodedMessage unknown = decode_v2i_message(wrap(p));
  ASSERT_EQ(unknown.status, DecodeStatus::kOk);
  EXPECT_EQ(std::get<FixWithheld>(unknown.body).reason, FixWithheldReason::kUnspecified);
  EXPECT_EQ(std::get<FixWithheld>(unknown.body).mount_cause, FixesWithheld::kUnknown);
  p.mutable_fix_withheld()->set_reason(static_cast<v2::FixWithheldReason>(-1));
  EXPECT_EQ(std::get<FixWithheld>(decode_v2i_message(wrap(p)).body).reason, FixWithheldReason::kUnspecified);

  for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity(), -0.01}) {
    v2::V2iPayload sigma;
    sigma.mutable_fix_withheld()->set_position_sigma_m(bad);
    EXPECT_EQ(decode_v2i_message(wrap(sigma)).status, DecodeStatus::kParseError) << bad;
    v2::V2iPayload bound;
    bound.mutable_fix_withheld()->set_max_position_sigma_m(bad);
    EXPECT_EQ(decode_v2i_message(wrap(bound)).status, DecodeStatus::kParseError) << bad;
  }
}

// Cut anywhere, a notice never decodes as one; padded beyond a datagram it is too large; and a body
// this code does not know (as field 7 is to an older receiver) is a payload without a body.
TEST(WireCodec, FixWithheldTruncatedOversizedAndUnknownBodies) {
  const std::vector<std::uint8_t> bytes = encode_v2i_message(withheld_notice());
  ASSERT_FALSE(bytes.empty());
  for (std::size_t n = 1; n < bytes.size(); ++n) {
    const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_NE(decode_v2i_message(cut).status, DecodeStatus::kOk) << "length " << n;
  }
  v2::SignedV2iMessage padded;
  padded.set_protocol_version(kProtocolVersion);
  EXPECT_TRUE(padded.ParseFromArray(bytes.data(), static_cast<int>(bytes.size())));
  padded.set_signature(std::string(kMaxDatagramBytes, 'x'));
  EXPECT_EQ(decode_v2i_message(serialise(padded)).status, DecodeStatus::kTooLarge);

  // V2iPayload field 15, length-delimited, 2 bytes: a body from a later version.
  v2::SignedV2iMessage later;
  later.set_protocol_version(kProtocolVersion);
  later.set_payload(std::string("\x7a\x02\x08\x01", 4));
  EXPECT_EQ(decode_v2i_message(serialise(later)).status, DecodeStatus::kNoBody);
}

TEST(WireCodec, EmptyAndOversizedInputsAreRefused) {
  EXPECT_EQ(decode_v2i_message({}).status, DecodeStatus::kEmpty);
  const std::vector<std::uint8_t> big(kMaxDatagramBytes + 1, 0x08);
  EXPECT_EQ(decode_v2i_message(big).status, DecodeStatus::kTooLarge);
  VehicleAnnouncement huge = testing::make_announcement(3, 1, kCodecNow);
  huge.reply_to.address.assign(2000, '1');
  EXPECT_TRUE(encode_v2i_message(huge).empty());
}

TEST(WireCodec, GarbageBytesAreAParseError) {
  // Field number 0 is invalid in the protobuf wire format; 0xFF... is an unterminated varint tag.
  EXPECT_EQ(decode_v2i_message(std::vector<std::uint8_t>(16, 0x00)).status, DecodeStatus::kParseError);
  EXPECT_EQ(decode_v2i_message(std::vector<std::uint8_t>(16, 0xFF)).status, DecodeStatus::kParseError);
  // Field 2 (payload) claiming 100 bytes of a 3-byte buffer.
  EXPECT_EQ(decode_v2i_message(std::vector<std::uint8_t>{0x12, 100, 0x08}).status, DecodeStatus::kParseError);
}

TEST(WireCodec, TruncatedMessagesNeverDecodeAsOk) {
  const std::vector<std::uint8_t> bytes = encode_v2i_message(testing::make_announcement(3, 1, kCodecNow));
  ASSERT_GT(bytes.size(), 20U);
  // Version (2 bytes), then the payload as one length-delimited field: cutting into it must fail the
  // parse; cutting before it leaves an envelope without a payload, which has no body.
  for (std::size_t n = 1; n < bytes.size(); ++n) {
    const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    const DecodeStatus s = decode_v2i_message(cut).status;
    EXPECT_TRUE(s == DecodeStatus::kParseError || s == DecodeStatus::kNoBody)
        << "length " << n << ": " << to_string(s);
  }
}

TEST(WireCodec, RandomBytesNeverCrash) {
  int parse_errors = 0;
  for (std::uint64_t trial = 0; trial < 3000; ++trial) {
    const std::size_t size = 1 + trial % 200;
    std::vector<std::uint8_t> bytes(size);
    for (std::size_t i = 0; i < size; ++i) {
      bytes[i] = static_cast<std::uint8_t>(mix64(trial * 1000 + i) & 0xFF);
    }
    const DecodedMessage out = decode_v2i_message(bytes);
    ASSERT_LT(static_cast<int>(out.status), static_cast<int>(DecodeStatus::kCount));
    if (out.status != DecodeStatus::kOk) {
      EXPECT_TRUE(std::holds_alternative<std::monostate>(out.body));
    }
    parse_errors += out.status == DecodeStatus::kParseError ? 1 : 0;
  }
  EXPECT_GT(parse_errors, 2000);
}

TEST(WireCodec, StructuralDefectsHaveTheirStatus) {
  v2::V2iPayload no_body;
  no_body.set_sequence(4);
  EXPECT_EQ(decode_v2i_message(wrap(no_body)).status, DecodeStatus::kNoBody);

  v2::V2iPayload short_covariance;
  auto* a = short_covariance.mutable_announcement();
  a->set_vehicle_id(3);
  for (int i = 0; i < 8; ++i) {
    a->mutable_pose_covariance()->add_row_major(1.0);
  }
  EXPECT_EQ(decode_v2i_message(wrap(short_covariance)).status, DecodeStatus::kMalformedCovariance);

  v2::SignedV2iMessage bad_payload;
  bad_payload.set_protocol_version(kProtocolVersion);
  bad_payload.set_payload(std::string(8, '\xFF'));
  EXPECT_EQ(decode_v2i_message(serialise(bad_payload)).status, DecodeStatus::kParseError);
}

// A version 1 datagram (the body inline in fields 2..4, no signature) is an unsupported version, and
// so is any other version, including a missing one.
TEST(WireCodec, OtherVersionsAreUnsupported) {
  // V2iMessage{protocol_version: 1, announcement: {vehicle_id: 3}} written out by hand: the version 1
  // schema is gone from proto/.
  const std::vector<std::uint8_t> v1 = {0x08, 0x01, 0x12, 0x02, 0x08, 0x03};
  EXPECT_EQ(decode_v2i_message(v1).status, DecodeStatus::kUnsupportedVersion);
  for (const std::uint32_t version : {0U, 1U, 3U, 7U}) {
    VehicleAnnouncement a = testing::make_announcement(3, 1, kCodecNow);
    a.protocol_version = version;
    EXPECT_EQ(decode_v2i_message(encode_v2i_message(a)).status, DecodeStatus::kUnsupportedVersion) << version;
  }
}

TEST(WireCodec, HeaderAndSignatureAreCarried) {
  security::Seed seed{};
  seed.fill(9);
  const security::SigningKey key(seed);
  const Correction c;
  const std::vector<std::uint8_t> bytes = encode_v2i_message(c, {kCodecNow + 5, 0xFFFFFFFEU}, &key);
  const DecodedEnvelope e = decode_envelope(bytes);
  ASSERT_EQ(e.status, DecodeStatus::kOk);
  EXPECT_EQ(e.envelope.signer_key_id, std::string(key.key_id().begin(), key.key_id().end()));
  ASSERT_EQ(e.envelope.signature.size(), security::kSignatureBytes);
  // The signature covers the context, a zero byte and the payload bytes as transmitted.
  const std::string expected = std::string(kSigningContext) + std::string(1, '\0') + e.envelope.payload;
  const std::vector<std::uint8_t> signed_bytes(expected.begin(), expected.end());
  EXPECT_EQ(signing_input(e.envelope.payload), signed_bytes);
  EXPECT_TRUE(
      security::verify_signature(key.public_key(), signed_bytes,
                                 std::span(reinterpret_cast<const std::uint8_t*>(e.envelope.signature.data()),
                                           e.envelope.signature.size())));
  const DecodedMessage m = decode_payload(e.envelope);
  ASSERT_EQ(m.status, DecodeStatus::kOk);
  EXPECT_EQ(m.header.generation_time, kCodecNow + 5);
  EXPECT_EQ(m.header.sequence, 0xFFFFFFFEU);
  // Unsigned: both fields empty.
  const DecodedEnvelope u = decode_envelope(encode_v2i_message(c));
  EXPECT_TRUE(u.envelope.signer_key_id.empty() && u.envelope.signature.empty());
}

TEST(WireCodec, FieldDefectsPassDecodingAndAreCaughtByValidation) {
  // Invalid UTF-8 in the address parses (the field is bytes) and is refused by validation.
  VehicleAnnouncement bad_address = testing::make_announcement(3, 1, kCodecNow);
  bad_address.reply_to.address = "\xC3\x28\xFF";
  const DecodedMessage b = decode_v2i_message(encode_v2i_message(bad_address));
  ASSERT_EQ(b.status, DecodeStatus::kOk);
  EXPECT_EQ(validate_announcement(std::get<VehicleAnnouncement>(b.body), kCodecNow),
            AnnouncementReason::kReplyAddressInvalid);
}

}  // namespace
}  // namespace rsu::v2i
