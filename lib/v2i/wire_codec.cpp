#include "v2i/wire_codec.h"

#include "proto/v2i.pb.h"

namespace rsu::v2i {
namespace {

namespace pb = ::rsu::v2i::v1;

bool read_covariance(const pb::Covariance3& in, Eigen::Matrix3d& out) {
  if (in.row_major_size() != 9) {
    return false;
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out(r, c) = in.row_major(3 * r + c);
    }
  }
  return true;
}

void write_covariance(const Eigen::Matrix3d& in, pb::Covariance3& out) {
  out.clear_row_major();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.add_row_major(in(r, c));
    }
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

void read_advertisement(const pb::RsuAdvertisement& in, RsuAdvertisement& out) {
  out.rsu_id = in.rsu_id();
  const auto& p = in.lidar_pose();
  out.lidar_pose = {p.x(), p.y(), p.z(), p.roll(), p.pitch(), p.yaw()};
  out.coverage_radius_m = in.coverage_radius_m();
  out.correction_port = in.correction_port();
  out.announcement_port = in.announcement_port();
}

std::vector<std::uint8_t> serialise(const pb::V2iMessage& message) {
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
    case DecodeStatus::kNoBody:
      return "no_body";
    case DecodeStatus::kMalformedCovariance:
      return "malformed_covariance";
    case DecodeStatus::kCount:
      break;
  }
  return "unknown";
}

DecodedMessage decode_v2i_message(std::span<const std::uint8_t> bytes) {
  DecodedMessage out;
  if (bytes.empty()) {
    out.status = DecodeStatus::kEmpty;
    return out;
  }
  if (bytes.size() > kMaxDatagramBytes) {
    out.status = DecodeStatus::kTooLarge;
    return out;
  }
  pb::V2iMessage message;
  if (!message.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    out.status = DecodeStatus::kParseError;
    return out;
  }
  switch (message.body_case()) {
    case pb::V2iMessage::kAnnouncement: {
      VehicleAnnouncement a;
      a.protocol_version = message.protocol_version();
      out.status = read_announcement(message.announcement(), a);
      out.body = std::move(a);
      break;
    }
    case pb::V2iMessage::kCorrection: {
      Correction c;
      c.protocol_version = message.protocol_version();
      out.status = read_correction(message.correction(), c);
      out.body = std::move(c);
      break;
    }
    case pb::V2iMessage::kAdvertisement: {
      RsuAdvertisement r;
      r.protocol_version = message.protocol_version();
      read_advertisement(message.advertisement(), r);
      out.status = DecodeStatus::kOk;
      out.body = std::move(r);
      break;
    }
    default:
      out.status = DecodeStatus::kNoBody;
      break;
  }
  if (out.status != DecodeStatus::kOk) {
    out.body = std::monostate{};
  }
  return out;
}

std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& a) {
  pb::V2iMessage message;
  message.set_protocol_version(a.protocol_version);
  auto& out = *message.mutable_announcement();
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
  return serialise(message);
}

std::vector<std::uint8_t> encode_v2i_message(const Correction& c) {
  pb::V2iMessage message;
  message.set_protocol_version(c.protocol_version);
  auto& out = *message.mutable_correction();
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
  return serialise(message);
}

std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& r) {
  pb::V2iMessage message;
  message.set_protocol_version(r.protocol_version);
  auto& out = *message.mutable_advertisement();
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
  return serialise(message);
}

}  // namespace rsu::v2i
