// SPDX-License-Identifier: Apache-2.0
#include "v2i/wire_codec.h"

#include <cmath>
#include <cstring>

#include "proto/v2i.pb.h"

namespace rsu::v2i {
namespace {

namespace pb = ::rsu::v2i::v2;

bool read_covariance(const pb::Covariance3& in, Eigen::Matrix3d& out) {
  if (in.row_major_size() != 9)
    return false;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      out(r, c) = in.row_major(3 * r + c);
  }
  return true;
}

void write_covariance(const Eigen::Matrix3d& in, pb::Covariance3& out) {
  out.clear_row_major();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      out.add_row_major(in(r, c));
  }
}

Pose2 read_pose(const pb::Pose2D& in) {
  return {in.x(), in.y(), in.yaw()};
}

void write_pose(const Pose2& in, pb::Pose2D& out) {
  out.set_x(in.x);
  out.set_y(in.y);
  out.set_yaw(in.yaw);
}

YawResolution read_yaw_resolution(pb::YawResolution in) {
  switch (in) {
    case pb::YAW_RESOLUTION_PRIOR:
      return YawResolution::kPrior;
    case pb::YAW_RESOLUTION_GEOMETRY:
      return YawResolution::kGeometry;
    default:
      // Unresolved, or a value added by a newer sender: assume the weakest claim.
      return YawResolution::kUnresolved;
  }
}

pb::YawResolution write_yaw_resolution(YawResolution in) {
  switch (in) {
    case YawResolution::kPrior:
      return pb::YAW_RESOLUTION_PRIOR;
    case YawResolution::kGeometry:
      return pb::YAW_RESOLUTION_GEOMETRY;
    case YawResolution::kUnresolved:
      break;
  }
  return pb::YAW_RESOLUTION_UNRESOLVED;
}

// A wire enum's value, or `unknown` for one this code does not know (a newer sender's, or garbage).
template <typename Enum>
Enum read_enum(int value, Enum known_end, Enum unknown) {
  return value >= 0 && value < static_cast<int>(known_end) ? static_cast<Enum>(value) : unknown;
}

// kUnknown is a receiver's reading, never sent: an RSU that has a reason names it.
pb::FixesWithheld write_fixes_withheld(FixesWithheld w) {
  return w == FixesWithheld::kUnknown || w == FixesWithheld::kCount ? pb::FIXES_WITHHELD_NONE
                                                                    : static_cast<pb::FixesWithheld>(w);
}

DecodeStatus read_announcement(const pb::VehicleAnnouncement& in, VehicleAnnouncement& out) {
  out.vehicle_id = in.vehicle_id();
  out.sequence = in.sequence();
  out.generation_time = in.generation_time_ns();
  out.size = {in.length_m(), in.width_m(), in.height_m()};
  out.reference_offset = {in.reference_offset_x_m(), in.reference_offset_y_m()};
  out.pose = read_pose(in.pose());
  if (!read_covariance(in.pose_covariance(), out.pose_covariance)) {
    return DecodeStatus::kMalformedCovariance;
  }
  if (in.has_speed_mps()) {
    out.speed_mps = in.speed_mps();
  }
  if (in.has_yaw_rate_rps()) {
    out.yaw_rate_rps = in.yaw_rate_rps();
  }
  out.reply_to.address = in.reply_to().address();
  out.reply_to.port = in.reply_to().port();
  return DecodeStatus::kOk;
}

DecodeStatus read_correction(const pb::Correction& in, Correction& out) {
  out.rsu_id = in.rsu_id();
  out.vehicle_id = in.vehicle_id();
  out.sequence = in.sequence();
  out.sweep_time = in.sweep_time_ns();
  out.pose = read_pose(in.pose());
  if (!read_covariance(in.pose_covariance(), out.pose_covariance)) {
    return DecodeStatus::kMalformedCovariance;
  }
  const auto& q = in.quality();
  out.quality.points_used = q.points_used();
  out.quality.faces_seen = q.faces_seen();
  out.quality.range_m = q.range_m();
  out.quality.yaw_resolution = read_yaw_resolution(q.yaw_resolution());
  out.quality.confidence = q.confidence();
  out.announcement_sequence = in.announcement_sequence();
  return DecodeStatus::kOk;
}

DecodeStatus read_advertisement(const pb::RsuAdvertisement& in, RsuAdvertisement& out) {
  out.rsu_id = in.rsu_id();
  const auto& p = in.lidar_pose();
  out.lidar_pose = {p.x(), p.y(), p.z(), p.roll(), p.pitch(), p.yaw()};
  out.coverage_radius_m = in.coverage_radius_m();
  out.correction_port = in.correction_port();
  out.announcement_port = in.announcement_port();
  out.fixes_withheld = read_enum(in.fixes_withheld(), FixesWithheld::kUnknown, FixesWithheld::kUnknown);
  out.mount_error_at_radius_m = in.mount_error_at_radius_m();
  return DecodeStatus::kOk;
}

// A detail the vehicle may print: printable ASCII, short (proto/v2i.proto AnnouncementRefusal).
DecodeStatus read_refusal(const pb::AnnouncementRefusal& in, AnnouncementRefusal& out) {
  out.rsu_id = in.rsu_id();
  out.vehicle_id = in.vehicle_id();
  out.announcement_sequence = in.announcement_sequence();
  out.reason = read_enum(in.reason(), RefusalReason::kCount, RefusalReason::kUnspecified);
  if (in.detail().size() > kMaxRefusalDetailBytes)
    return DecodeStatus::kParseError;
  for (const char c : in.detail()) {
    if (c < 0x20 || c > 0x7E)
      return DecodeStatus::kParseError;
  }
  out.detail = in.detail();
  return DecodeStatus::kOk;
}

// A sigma is a length or absent (proto/v2i.proto FixWithheld): anything else makes the notice unreadable.
bool read_sigma(bool present, double value, std::optional<double>& out) {
  if (present)
    out = value;
  return !present || (std::isfinite(value) && value >= 0.0);
}

DecodeStatus read_fix_withheld(const pb::FixWithheld& in, FixWithheld& out) {
  out.rsu_id = in.rsu_id();
  out.vehicle_id = in.vehicle_id();
  out.announcement_sequence = in.announcement_sequence();
  out.sweep_time = in.sweep_time_ns();
  out.reason = read_enum(in.reason(), FixWithheldReason::kCount, FixWithheldReason::kUnspecified);
  out.packets_lost_nearby = in.packets_lost_nearby();
  out.mount_cause = read_enum(in.mount_cause(), FixesWithheld::kUnknown, FixesWithheld::kUnknown);
  const bool sigmas_read =
      read_sigma(in.has_position_sigma_m(), in.position_sigma_m(), out.position_sigma_m) &&
      read_sigma(in.has_max_position_sigma_m(), in.max_position_sigma_m(), out.max_position_sigma_m);
  return sigmas_read ? DecodeStatus::kOk : DecodeStatus::kParseError;
}

// One body read by `read`, carrying the envelope's protocol version; its status.
template <typename Wire, typename Body>
DecodeStatus read_body(const Wire& in, DecodeStatus (*read)(const Wire&, Body&), std::uint32_t version,
                       MessageBody& out) {
  Body body;
  body.protocol_version = version;
  const DecodeStatus status = read(in, body);
  out = std::move(body);
  return status;
}

void write_announcement(const VehicleAnnouncement& a, pb::VehicleAnnouncement& out) {
  out.set_vehicle_id(a.vehicle_id);
  out.set_sequence(a.sequence);
  out.set_generation_time_ns(a.generation_time);
  out.set_length_m(a.size.length_m);
  out.set_width_m(a.size.width_m);
  out.set_height_m(a.size.height_m);
  out.set_reference_offset_x_m(a.reference_offset.x());
  out.set_reference_offset_y_m(a.reference_offset.y());
  write_pose(a.pose, *out.mutable_pose());
  write_covariance(a.pose_covariance, *out.mutable_pose_covariance());
  if (a.speed_mps) {
    out.set_speed_mps(*a.speed_mps);
  }
  if (a.yaw_rate_rps) {
    out.set_yaw_rate_rps(*a.yaw_rate_rps);
  }
  out.mutable_reply_to()->set_address(a.reply_to.address);
  out.mutable_reply_to()->set_port(a.reply_to.port);
}

void write_correction(const Correction& c, pb::Correction& out) {
  out.set_rsu_id(c.rsu_id);
  out.set_vehicle_id(c.vehicle_id);
  out.set_sequence(c.sequence);
  out.set_sweep_time_ns(c.sweep_time);
  write_pose(c.pose, *out.mutable_pose());
  write_covariance(c.pose_covariance, *out.mutable_pose_covariance());
  auto& q = *out.mutable_quality();
  q.set_points_used(c.quality.points_used);
  q.set_faces_seen(c.quality.faces_seen);
  q.set_range_m(c.quality.range_m);
  q.set_yaw_resolution(write_yaw_resolution(c.quality.yaw_resolution));
  q.set_confidence(c.quality.confidence);
  out.set_announcement_sequence(c.announcement_sequence);
}

void write_advertisement(const RsuAdvertisement& r, pb::RsuAdvertisement& out) {
  out.set_rsu_id(r.rsu_id);
  auto& p = *out.mutable_lidar_pose();
  p.set_x(r.lidar_pose.x);
  p.set_y(r.lidar_pose.y);
  p.set_z(r.lidar_pose.z);
  p.set_roll(r.lidar_pose.roll);
  p.set_pitch(r.lidar_pose.pitch);
  p.set_yaw(r.lidar_pose.yaw);
  out.set_coverage_radius_m(r.coverage_radius_m);
  out.set_correction_port(r.correction_port);
  out.set_announcement_port(r.announcement_port);
  out.set_fixes_withheld(write_fixes_withheld(r.fixes_withheld));
  out.set_mount_error_at_radius_m(r.mount_error_at_radius_m);
}

void write_refusal(const AnnouncementRefusal& r, pb::AnnouncementRefusal& out) {
  out.set_rsu_id(r.rsu_id);
  out.set_vehicle_id(r.vehicle_id);
  out.set_announcement_sequence(r.announcement_sequence);
  out.set_reason(static_cast<pb::RefusalReason>(r.reason));
  out.set_detail(r.detail.substr(0, kMaxRefusalDetailBytes));
}

void write_fix_withheld(const FixWithheld& f, pb::FixWithheld& out) {
  out.set_rsu_id(f.rsu_id);
  out.set_vehicle_id(f.vehicle_id);
  out.set_announcement_sequence(f.announcement_sequence);
  out.set_sweep_time_ns(f.sweep_time);
  out.set_reason(static_cast<pb::FixWithheldReason>(f.reason));
  if (f.position_sigma_m)
    out.set_position_sigma_m(*f.position_sigma_m);
  if (f.max_position_sigma_m)
    out.set_max_position_sigma_m(*f.max_position_sigma_m);
  out.set_packets_lost_nearby(f.packets_lost_nearby);
  out.set_mount_cause(write_fixes_withheld(f.mount_cause));
}

// Wraps a filled payload in the envelope, signing the payload's serialized bytes as they go out.
std::vector<std::uint8_t> seal(pb::V2iPayload& payload, std::uint32_t protocol_version,
                               const MessageHeader& header, const security::SigningKey* signer) {
  payload.set_generation_time_ns(header.generation_time);
  payload.set_sequence(header.sequence);
  pb::SignedV2iMessage message;
  message.set_protocol_version(protocol_version);
  if (!payload.SerializeToString(message.mutable_payload())) {
    return {};
  }
  if (signer != nullptr) {
    const security::Signature signature = signer->sign(signing_input(message.payload()));
    message.set_signer_key_id(signer->key_id().data(), signer->key_id().size());
    message.set_signature(signature.data(), signature.size());
  }
  const std::size_t size = message.ByteSizeLong();
  if (size > kMaxDatagramBytes) {
    return {};
  }
  std::vector<std::uint8_t> bytes(size);
  if (!message.SerializeToArray(bytes.data(), static_cast<int>(size))) {
    return {};
  }
  return bytes;
}

}  // namespace

const char* to_string(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kEmpty:
      return "empty";
    case DecodeStatus::kTooLarge:
      return "too_large";
    case DecodeStatus::kParseError:
      return "parse_error";
    case DecodeStatus::kUnsupportedVersion:
      return "unsupported_version";
    case DecodeStatus::kNoBody:
      return "no_body";
    case DecodeStatus::kMalformedCovariance:
      return "malformed_covariance";
    case DecodeStatus::kCount:
      break;
  }
  return "unknown";
}

DecodedEnvelope decode_envelope(std::span<const std::uint8_t> bytes) {
  DecodedEnvelope out;
  if (bytes.empty()) {
    out.status = DecodeStatus::kEmpty;
    return out;
  }
  if (bytes.size() > kMaxDatagramBytes) {
    out.status = DecodeStatus::kTooLarge;
    return out;
  }
  pb::SignedV2iMessage message;
  if (!message.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    out.status = DecodeStatus::kParseError;
    return out;
  }
  if (message.protocol_version() != kProtocolVersion) {
    out.status = DecodeStatus::kUnsupportedVersion;
    return out;
  }
  out.envelope.protocol_version = message.protocol_version();
  out.envelope.payload = std::move(*message.mutable_payload());
  out.envelope.signer_key_id = std::move(*message.mutable_signer_key_id());
  out.envelope.signature = std::move(*message.mutable_signature());
  out.status = DecodeStatus::kOk;
  return out;
}

DecodedMessage decode_payload(const Envelope& envelope) {
  DecodedMessage out;
  pb::V2iPayload message;
  if (!message.ParseFromString(envelope.payload)) {
    out.status = DecodeStatus::kParseError;
    return out;
  }
  out.header.generation_time = message.generation_time_ns();
  out.header.sequence = message.sequence();
  const std::uint32_t version = envelope.protocol_version;
  switch (message.body_case()) {
    case pb::V2iPayload::kAnnouncement:
      out.status = read_body(message.announcement(), read_announcement, version, out.body);
      break;
    case pb::V2iPayload::kCorrection:
      out.status = read_body(message.correction(), read_correction, version, out.body);
      break;
    case pb::V2iPayload::kAdvertisement:
      out.status = read_body(message.advertisement(), read_advertisement, version, out.body);
      break;
    case pb::V2iPayload::kRefusal:
      out.status = read_body(message.refusal(), read_refusal, version, out.body);
      break;
    case pb::V2iPayload::kFixWithheld:
      out.status = read_body(message.fix_withheld(), read_fix_withheld, version, out.body);
      break;
    default:
      out.status = DecodeStatus::kNoBody;
      break;
  }
  if (out.status != DecodeStatus::kOk) {
    out.body = std::monostate{};
  }
  return out;
}

DecodedMessage decode_v2i_message(std::span<const std::uint8_t> bytes) {
  const DecodedEnvelope envelope = decode_envelope(bytes);
  if (envelope.status != DecodeStatus::kOk) {
    DecodedMessage out;
    out.status = envelope.status;
    return out;
  }
  return decode_payload(envelope.envelope);
}

std::vector<std::uint8_t> signing_input(std::string_view payload) {
  // Sized once and filled with memcpy (GCC 12 warns falsely about vector::insert growing here).
  std::vector<std::uint8_t> out(kSigningContext.size() + 1 + payload.size());
  std::memcpy(out.data(), kSigningContext.data(), kSigningContext.size());
  out[kSigningContext.size()] = 0;
  if (!payload.empty()) {
    std::memcpy(out.data() + kSigningContext.size() + 1, payload.data(), payload.size());
  }
  return out;
}

std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& a, const MessageHeader& header,
                                             const security::SigningKey* signer) {
  pb::V2iPayload payload;
  write_announcement(a, *payload.mutable_announcement());
  return seal(payload, a.protocol_version, header, signer);
}

std::vector<std::uint8_t> encode_v2i_message(const Correction& c, const MessageHeader& header,
                                             const security::SigningKey* signer) {
  pb::V2iPayload payload;
  write_correction(c, *payload.mutable_correction());
  return seal(payload, c.protocol_version, header, signer);
}

std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& r, const MessageHeader& header,
                                             const security::SigningKey* signer) {
  pb::V2iPayload payload;
  write_advertisement(r, *payload.mutable_advertisement());
  return seal(payload, r.protocol_version, header, signer);
}

std::vector<std::uint8_t> encode_v2i_message(const AnnouncementRefusal& r, const MessageHeader& header,
                                             const security::SigningKey* signer) {
  pb::V2iPayload payload;
  write_refusal(r, *payload.mutable_refusal());
  return seal(payload, r.protocol_version, header, signer);
}

std::vector<std::uint8_t> encode_v2i_message(const FixWithheld& f, const MessageHeader& header,
                                             const security::SigningKey* signer) {
  pb::V2iPayload payload;
  write_fix_withheld(f, *payload.mutable_fix_withheld());
  return seal(payload, f.protocol_version, header, signer);
}

std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& a) {
  return encode_v2i_message(a, {a.generation_time, a.sequence}, nullptr);
}

std::vector<std::uint8_t> encode_v2i_message(const Correction& c) {
  return encode_v2i_message(c, {c.sweep_time, c.sequence}, nullptr);
}

std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& r) {
  return encode_v2i_message(r, {}, nullptr);
}

std::vector<std::uint8_t> encode_v2i_message(const AnnouncementRefusal& r) {
  return encode_v2i_message(r, {}, nullptr);
}

std::vector<std::uint8_t> encode_v2i_message(const FixWithheld& f) {
  return encode_v2i_message(f, {}, nullptr);
}

}  // namespace rsu::v2i
