// SPDX-License-Identifier: Apache-2.0
// The Ouster decoder behind the decoder seam (lidar/lidar_decoder.h): OS0 / OS1 / OS2 lidar packets
// of one sensor, described by its metadata JSON (ouster_metadata.h), into points (ouster_decoder.h).
//
//   - Payloads: lidar packets of the metadata's profile are data; 48-byte IMU packets are auxiliary
//     ("imu": the sensor sends them to port 7503 by default); a lidar packet whose every column is
//     flagged invalid (outside the azimuth window) carries no points and is auxiliary too
//     ("no_valid_column"). Everything else is refused with ouster_decoder.h's reasons.
//   - Points keep the sensor's own clock (TIME_FROM_INTERNAL_OSC: time since the sensor started;
//     PTP or GPS modes: that clock); first_ns is the packet's first valid column, next_ns when the
//     next packet is due: one column after its last, or, at the end of an azimuth window, when the
//     sweep reaches the window's first column again.
//   - Geometry: the rotation rate is the metadata's lidar mode (10 or 20 Hz; the column timestamps of
//     real captures follow it within 0.1 %), ring offsets are the beams' azimuth offsets, the rotation
//     starts where the options say (scan phase).
//   - Notices: the metadata fields the SDK's defaults replaced; the first packet of another sensor or
//     another initialization of this one.
// Single-return profiles report the strongest return: every point is tagged so, whatever
// ReturnSelection asks.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lidar/lidar_decoder.h"
#include "lidar/ouster/ouster_decoder.h"

namespace rsu::lidar::ouster {

class OusterLidarDecoder final : public LidarDecoder {
 public:
  // Throws std::invalid_argument for an unusable configuration.
  OusterLidarDecoder(Metadata metadata, std::string metadata_source, double rotation_start_azimuth_deg = 0.0,
                     DecoderConfig config = {});

  PacketOutcome decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                       std::vector<LidarPoint>& out) override;
  const SweepGeometry& geometry() const override { return geometry_; }
  SensorPorts default_ports() const override;
  std::string_view model_name() const override { return model_name_; }
  std::vector<std::pair<std::string, std::uint64_t>> counters() const override;
  std::vector<std::string> take_notices() override;

  const Decoder& decoder() const { return decoder_; }

 private:
  TimeNs next_packet_ns(const PacketInfo& info) const;
  void note_refusal(PacketResult result, std::span<const std::uint8_t> payload);

  Decoder decoder_;
  PacketReader reader_;  // to name the sensor of a refused packet
  std::string source_;
  std::string model_name_;
  SweepGeometry geometry_;
  TimeNs column_ns_ = 0;
  std::uint64_t empty_packets_ = 0;
  bool told_serial_ = false;
  bool told_init_id_ = false;
  std::vector<std::string> notices_;
};

// Whether `model` names an Ouster sensor: "ouster" (whatever the metadata says) or os0 / os1 / os2
// with 16, 32, 64 or 128 beams ("os1-128").
bool is_ouster_model(std::string_view model);

// The decoder for `model` from the metadata text. Throws std::invalid_argument for no or broken
// metadata (the message locates the field: "<source>:<line>: <field>: ...") or a metadata file that
// describes another model.
std::unique_ptr<LidarDecoder> make_ouster_decoder(std::string_view model, const std::string& metadata_text,
                                                  const std::string& metadata_source,
                                                  double rotation_start_azimuth_deg);

}  // namespace rsu::lidar::ouster
