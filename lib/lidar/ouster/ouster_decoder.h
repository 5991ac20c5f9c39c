// SPDX-License-Identifier: Apache-2.0
// Turns one Ouster sensor's lidar packets into points (ouster_packet.h for the bytes,
// ouster_geometry.h for where they point), with every refusal counted by reason.
//
// Each point: xyz in the sensor frame (x forward, y left, z up, origin at the centre of the base),
// ring = pixel row (the packet's channel order, as the Velodyne decoders' ring: for Ouster row 0 is
// the highest beam), time = its column's timestamp (the sensor's clock, ns; all pixels of a column
// fire together), intensity = reflectivity (clamped to 255), azimuth = the beam's.
//
// Rotations: a packet whose frame id differs from the current one begins a new frame; one frame
// behind is a late packet and refused (as the SDK does). Within a frame the measurement ids must
// rise; columns the stream skipped (lost packets) are counted and never filled in or interpolated.
// The frame is complete once the last column of the metadata's column window has been decoded.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "lidar/ouster/ouster_geometry.h"
#include "lidar/ouster/ouster_metadata.h"
#include "lidar/ouster/ouster_packet.h"
#include "lidar/point.h"

namespace rsu::lidar::ouster {

// Checks run in this order; the first failure refuses the packet whole.
enum class PacketResult {
  accepted,
  imu_packet,          // a 48-byte IMU packet (the sensor sends them to port 7503 by default): ignored
  wrong_size,          // not the size of the metadata's profile, pixels and columns per packet
  not_lidar_packet,    // eUDP packet type is not 1
  wrong_serial,        // eUDP header names a sensor other than the metadata's prod_sn
  wrong_init_id,       // eUDP header from another initialization than the metadata's: re-read it
  bad_timestamp,       // a valid column's timestamp does not fit signed 64-bit ns
  bad_measurement_id,  // a valid column's measurement id >= columns_per_frame, or not one more than
                       // the previous valid column's
  frame_id_mismatch,   // LEGACY: the valid columns of one packet carry different frame ids
  frame_behind,        // a packet of the previous frame after the next one began (late / reordered)
  column_behind,       // a column at or before one already decoded in this frame (duplicate / reordered)
};
std::string_view to_string(PacketResult result);

struct DecoderStats {
  std::uint64_t accepted = 0;
  std::uint64_t imu_packets = 0;
  std::uint64_t wrong_size = 0;
  std::uint64_t not_lidar_packet = 0;
  std::uint64_t wrong_serial = 0;
  std::uint64_t wrong_init_id = 0;
  std::uint64_t bad_timestamp = 0;
  std::uint64_t bad_measurement_id = 0;
  std::uint64_t frame_id_mismatch = 0;
  std::uint64_t frame_behind = 0;
  std::uint64_t column_behind = 0;

  std::uint64_t columns_decoded = 0;
  std::uint64_t columns_invalid = 0;  // status says not valid (outside the azimuth window, dropped)
  std::uint64_t columns_skipped = 0;  // window columns a frame went past without receiving (lost)
  std::uint64_t frames = 0;           // frames begun
  std::uint64_t frames_complete = 0;  // frames whose whole column window arrived
  std::uint64_t frame_id_jumps = 0;   // a frame id neither the same, the next nor the previous
  std::uint64_t points = 0;
  std::uint64_t no_return = 0;  // range 0
  std::uint64_t too_close = 0;  // range below the minimum

  std::uint64_t packets() const;  // all, IMU packets included
  std::uint64_t rejected() const;
  // The count of packets with this outcome.
  std::uint64_t& of(PacketResult result);
  std::uint64_t of(PacketResult result) const { return const_cast<DecoderStats&>(*this).of(result); }
};

struct DecoderConfig {
  // Returns closer than this (range from the lidar origin) are dropped: none then lies inside the
  // sensor body. 0.5 m is the firmware's own default minimum (min_range_threshold_cm).
  double min_range_m = 0.5;
  // Refuse eUDP packets of another initialization than the metadata's (as the SDK does by default):
  // a re-initialised sensor may have changed mode, and then its metadata must be read again.
  bool check_initialization_id = true;
};

// What the last decoded packet did to the frame sequence.
struct PacketInfo {
  PacketResult result = PacketResult::accepted;
  bool begins_frame = false;     // its frame id began a new frame (the previous one ended before it)
  bool completes_frame = false;  // it held the last column of the window
  std::uint16_t frame_id = 0;
  int first_column = -1;  // measurement ids of its first and last valid column; -1 if none
  int last_column = -1;
  TimeNs first_time_ns = 0;  // their timestamps (sensor clock)
  TimeNs last_time_ns = 0;
  std::size_t points = 0;
};

class Decoder {
 public:
  // Throws std::invalid_argument if the configuration is not finite and non-negative.
  explicit Decoder(Metadata metadata, DecoderConfig config = {});

  // Appends the packet's returns to `out` (nothing unless accepted). Never throws on packet content.
  PacketResult decode(std::span<const std::uint8_t> payload, std::vector<LidarPoint>& out);

  const PacketInfo& last_packet() const { return last_; }
  const DecoderStats& stats() const { return stats_; }
  const Metadata& metadata() const { return metadata_; }
  const BeamGeometry& geometry() const { return geometry_; }

 private:
  PacketResult check_header(std::span<const std::uint8_t> payload) const;
  PacketResult check_columns(std::span<const std::uint8_t> payload, PacketInfo& info) const;
  PacketResult check_sequence(const PacketInfo& info) const;
  void advance_frame(PacketInfo& info);
  void append_points(std::span<const std::uint8_t> payload, std::vector<LidarPoint>& out);
  int window_columns_between(int from, int to) const;  // window columns in [from, to)
  void count(PacketResult result);

  Metadata metadata_;
  DecoderConfig config_;
  PacketReader reader_;
  BeamGeometry geometry_;
  std::uint32_t min_range_mm_ = 0;
  DecoderStats stats_;
  PacketInfo last_;

  bool in_frame_ = false;
  std::uint16_t frame_id_ = 0;
  int next_column_ = 0;  // the lowest measurement id the current frame can still take
  int received_ = 0;     // window columns decoded in the current frame
};

}  // namespace rsu::lidar::ouster
