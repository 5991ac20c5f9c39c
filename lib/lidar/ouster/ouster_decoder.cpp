// SPDX-License-Identifier: Apache-2.0
// Ouster lidar packet decoder (see ouster_decoder.h).
#include "lidar/ouster/ouster_decoder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace rsu::lidar::ouster {
namespace {

constexpr std::uint64_t kMaxTimestampNs = static_cast<std::uint64_t>(std::numeric_limits<TimeNs>::max());

// Points keep the azimuth as float; a double just below 2 pi may round to float(2 pi), outside
// [0, 2 pi): that direction is azimuth 0.
float float_azimuth(double azimuth_rad) {
  const auto a = static_cast<float>(azimuth_rad);
  return a >= static_cast<float>(2.0 * std::numbers::pi) ? 0.0F : a;
}

}  // namespace

std::string_view to_string(PacketResult result) {
  switch (result) {
    case PacketResult::accepted:
      return "accepted";
    case PacketResult::imu_packet:
      return "imu_packet";
    case PacketResult::wrong_size:
      return "wrong_size";
    case PacketResult::not_lidar_packet:
      return "not_lidar_packet";
    case PacketResult::wrong_serial:
      return "wrong_serial";
    case PacketResult::wrong_init_id:
      return "wrong_init_id";
    case PacketResult::bad_timestamp:
      return "bad_timestamp";
    case PacketResult::bad_measurement_id:
      return "bad_measurement_id";
    case PacketResult::frame_id_mismatch:
      return "frame_id_mismatch";
    case PacketResult::frame_behind:
      return "frame_behind";
    case PacketResult::column_behind:
      return "column_behind";
  }
  return "unknown";
}

std::uint64_t DecoderStats::packets() const {
  return accepted + imu_packets + rejected();
}

std::uint64_t& DecoderStats::of(PacketResult result) {
  switch (result) {
    case PacketResult::accepted:
      return accepted;
    case PacketResult::imu_packet:
      return imu_packets;
    case PacketResult::wrong_size:
      return wrong_size;
    case PacketResult::not_lidar_packet:
      return not_lidar_packet;
    case PacketResult::wrong_serial:
      return wrong_serial;
    case PacketResult::wrong_init_id:
      return wrong_init_id;
    case PacketResult::bad_timestamp:
      return bad_timestamp;
    case PacketResult::bad_measurement_id:
      return bad_measurement_id;
    case PacketResult::frame_id_mismatch:
      return frame_id_mismatch;
    case PacketResult::frame_behind:
      return frame_behind;
    case PacketResult::column_behind:
      break;
  }
  return column_behind;
}

std::uint64_t DecoderStats::rejected() const {
  return wrong_size + not_lidar_packet + wrong_serial + wrong_init_id + bad_timestamp + bad_measurement_id +
         frame_id_mismatch + frame_behind + column_behind;
}

Decoder::Decoder(Metadata metadata, DecoderConfig config)
    : metadata_(std::move(metadata)),
      config_(config),
      reader_(metadata_.profile, metadata_.pixels_per_column, metadata_.columns_per_packet),
      geometry_(metadata_) {
  if (!std::isfinite(config_.min_range_m) || config_.min_range_m < 0.0 || config_.min_range_m > 1000.0) {
    throw std::invalid_argument("Ouster decoder: min_range_m must be within [0, 1000] m");
  }
  if (metadata_.columns_per_frame <= 0 || metadata_.pixels_per_column <= 0 ||
      metadata_.columns_per_packet <= 0 ||
      metadata_.beam_altitude_deg.size() != static_cast<std::size_t>(metadata_.pixels_per_column) ||
      metadata_.beam_azimuth_deg.size() != metadata_.beam_altitude_deg.size()) {
    throw std::invalid_argument("Ouster decoder: metadata without a consistent format (use parse_metadata)");
  }
  min_range_mm_ = static_cast<std::uint32_t>(std::ceil(config_.min_range_m * 1000.0));
}

void Decoder::count(PacketResult result) {
  last_.result = result;
  ++stats_.of(result);
}

PacketResult Decoder::check_header(std::span<const std::uint8_t> payload) const {
  if (metadata_.profile == UdpProfile::legacy) {
    return PacketResult::accepted;
  }
  const PacketHeader h = reader_.header(payload);
  if (h.packet_type != kLidarPacketType) {
    return PacketResult::not_lidar_packet;
  }
  if (metadata_.serial_number && h.serial_number != *metadata_.serial_number) {
    return PacketResult::wrong_serial;
  }
  if (config_.check_initialization_id && metadata_.initialization_id &&
      h.initialization_id != *metadata_.initialization_id) {
    return PacketResult::wrong_init_id;
  }
  return PacketResult::accepted;
}

PacketResult Decoder::check_columns(std::span<const std::uint8_t> payload, PacketInfo& info) const {
  int previous_slot = -1;
  for (int c = 0; c < metadata_.columns_per_packet; ++c) {
    const ColumnHeader col = reader_.column(payload, c);
    if (!col.valid()) {
      continue;
    }
    if (col.timestamp_ns > kMaxTimestampNs) {
      return PacketResult::bad_timestamp;
    }
    const int m = col.measurement_id;
    // Columns of one packet are consecutive measurements, whatever lies between valid ones.
    if (m >= metadata_.columns_per_frame ||
        (previous_slot >= 0 && m != info.last_column + (c - previous_slot))) {
      return PacketResult::bad_measurement_id;
    }
    if (previous_slot < 0) {
      info.first_column = m;
      info.first_time_ns = static_cast<TimeNs>(col.timestamp_ns);
      info.frame_id = col.frame_id;
    } else if (col.frame_id != info.frame_id) {
      return PacketResult::frame_id_mismatch;
    }
    info.last_column = m;
    info.last_time_ns = static_cast<TimeNs>(col.timestamp_ns);
    previous_slot = c;
  }
  return PacketResult::accepted;
}

PacketResult Decoder::check_sequence(const PacketInfo& info) const {
  if (info.first_column < 0 || !in_frame_) {
    return PacketResult::accepted;
  }
  if (info.frame_id == frame_id_) {
    return info.first_column < next_column_ ? PacketResult::column_behind : PacketResult::accepted;
  }
  if (info.frame_id == static_cast<std::uint16_t>(frame_id_ - 1)) {
    return PacketResult::frame_behind;
  }
  return PacketResult::accepted;
}

int Decoder::window_columns_between(int from, int to) const {
  const auto overlap = [&](int lo, int hi) { return std::max(0, std::min(to, hi) - std::max(from, lo)); };
  const int first = metadata_.column_window_first;
  const int last = metadata_.column_window_last;
  if (first <= last) {
    return overlap(first, last + 1);
  }
  return overlap(0, last + 1) + overlap(first, metadata_.columns_per_frame);
}

void Decoder::advance_frame(PacketInfo& info) {
  if (info.first_column < 0) {
    return;  // only invalid columns: nothing about the frame sequence
  }
  const bool stream_start = !in_frame_;
  if (stream_start || info.frame_id != frame_id_) {
    if (!stream_start) {
      stats_.columns_skipped +=
          static_cast<std::uint64_t>(window_columns_between(next_column_, metadata_.columns_per_frame));
      if (info.frame_id != static_cast<std::uint16_t>(frame_id_ + 1)) {
        ++stats_.frame_id_jumps;
      }
    }
    in_frame_ = true;
    frame_id_ = info.frame_id;
    // A stream that starts mid-frame has not skipped the columns before its first packet.
    next_column_ = stream_start ? info.first_column : 0;
    received_ = 0;
    info.begins_frame = true;
    ++stats_.frames;
  }
  stats_.columns_skipped +=
      static_cast<std::uint64_t>(window_columns_between(next_column_, info.first_column));
  received_ += window_columns_between(info.first_column, info.last_column + 1);
  next_column_ = info.last_column + 1;
  const int end = metadata_.column_window_first <= metadata_.column_window_last
                      ? metadata_.column_window_last
                      : metadata_.columns_per_frame - 1;
  if (info.first_column <= end && end <= info.last_column) {
    info.completes_frame = true;
    if (received_ == metadata_.columns_in_window()) {
      ++stats_.frames_complete;
    }
  }
}

void Decoder::append_points(std::span<const std::uint8_t> payload, std::vector<LidarPoint>& out) {
  const std::size_t before = out.size();
  out.reserve(before + static_cast<std::size_t>(metadata_.columns_per_packet * metadata_.pixels_per_column));
  for (int c = 0; c < metadata_.columns_per_packet; ++c) {
    const ColumnHeader col = reader_.column(payload, c);
    if (!col.valid()) {
      ++stats_.columns_invalid;
      continue;
    }
    ++stats_.columns_decoded;
    const int m = col.measurement_id;
    for (int row = 0; row < metadata_.pixels_per_column; ++row) {
      const Pixel px = reader_.pixel(payload, c, row);
      if (px.range_mm == 0) {
        ++stats_.no_return;
        continue;
      }
      if (px.range_mm < min_range_mm_) {
        ++stats_.too_close;
        continue;
      }
      const Eigen::Vector3d p = geometry_.point(row, m, static_cast<double>(px.range_mm));
      LidarPoint point;
      point.x = static_cast<float>(p.x());
      point.y = static_cast<float>(p.y());
      point.z = static_cast<float>(p.z());
      point.intensity = static_cast<float>(std::min<std::uint16_t>(px.reflectivity, 255));
      point.ring = static_cast<std::uint16_t>(row);
      point.azimuth_rad = float_azimuth(geometry_.azimuth_rad(row, m));
      point.time_ns = static_cast<TimeNs>(col.timestamp_ns);
      out.push_back(point);
    }
  }
  last_.points = out.size() - before;
  stats_.points += last_.points;
}

PacketResult Decoder::decode(std::span<const std::uint8_t> payload, std::vector<LidarPoint>& out) {
  last_ = PacketInfo{};
  const std::size_t expected = reader_.layout().packet_bytes;
  if (payload.size() != expected) {
    count(payload.size() == kImuPacketBytes ? PacketResult::imu_packet : PacketResult::wrong_size);
    return last_.result;
  }
  PacketInfo info;
  PacketResult result = check_header(payload);
  if (result == PacketResult::accepted) {
    result = check_columns(payload, info);
  }
  if (result == PacketResult::accepted) {
    result = check_sequence(info);
  }
  if (result != PacketResult::accepted) {
    count(result);
    return result;
  }
  advance_frame(info);
  last_ = info;
  append_points(payload, out);
  count(PacketResult::accepted);
  return PacketResult::accepted;
}

}  // namespace rsu::lidar::ouster
