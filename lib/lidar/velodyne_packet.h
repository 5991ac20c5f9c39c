// SPDX-License-Identifier: Apache-2.0
// The Velodyne data packet (docs/design.md §2): the 1206-byte UDP payload on port 2368, and the 512-byte
// position packet on port 8308. Byte layout from the VLP-16, VLP-32C and HDL-32E user manuals ("Data
// Packet Structure", "Position Packet Structure"):
//
//   12 data blocks of 100 bytes: 0xFF 0xEE, azimuth uint16 LE (0.01 deg),
//                                32 x {distance uint16 LE (distance units), reflectivity uint8}
//   byte 1200: timestamp uint32 LE, microseconds past the top of the hour (of the packet's first firing
//              on the VLP-16 / VLP-32C; of its end on the HDL-32E: SensorModel)
//   byte 1204: return mode (0x37 strongest, 0x38 last, 0x39 dual: blocks 2k, 2k + 1 hold the last and
//              the strongest echo of the same firings, or the second strongest when they are one)
//   byte 1205: product id (0x21 HDL-32E, 0x22 VLP-16, 0x28 VLP-32C, ...)
// A distance of 0 means no return. Beam angles and firing times come from firing_schedule.h, the rule
// shared with the simulator. This file is the byte codec; lidar/velodyne_decoder.h turns packets into
// points.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "common/time.h"
#include "lidar/firing_schedule.h"
#include "lidar/point.h"
#include "lidar/sensor_model.h"

namespace rsu::lidar {

constexpr std::size_t kPacketBytes = 1206;
constexpr std::size_t kBlockBytes = 100;
constexpr std::size_t kTimestampOffset = 1200;
constexpr std::size_t kReturnModeOffset = 1204;
constexpr std::size_t kProductIdOffset = 1205;
constexpr std::uint8_t kReturnStrongest = 0x37;
constexpr std::uint8_t kReturnLast = 0x38;
constexpr std::uint8_t kReturnDual = 0x39;
constexpr std::uint16_t kVelodyneDataPort = 2368;
constexpr std::uint16_t kVelodynePositionPort = 8308;
constexpr std::size_t kPositionPacketBytes = 512;

// The content of one packet, channel by channel (channel numbering as in firing_schedule.h).
struct PacketReturns {
  PacketBlocks blocks;
  std::array<std::array<std::uint16_t, kChannelsPerBlock>, kBlocksPerPacket> distance_raw{};  // 0 = none
  std::array<std::array<std::uint8_t, kChannelsPerBlock>, kBlocksPerPacket> reflectivity{};
  std::uint8_t return_mode = kReturnStrongest;  // blocks.dual_return mirrors kReturnDual
  std::uint8_t product_id = 0;                  // as parsed (encode_packet writes the model's)
};

// Range in metres -> packet distance units, rounded to nearest; 0 (no return) outside
// [min_range_m, max_range_m] or for NaN.
std::uint16_t quantize_distance(const SensorModel& model, double range_m);

// Writes the packet. The timestamp is first_firing_ns modulo one hour, in whole microseconds
// (floored). Throws std::invalid_argument if the model has no packet format or is invalid.
void encode_packet(const SensorModel& model, const PacketReturns& returns,
                   std::span<std::uint8_t, kPacketBytes> out);

// Why a packet was accepted or rejected. Checks run in this order and the first failure is reported:
// size, product id, return mode, block flags, block azimuths, timestamp. A known product other than
// the configured model's is not a refusal: the operator's model wins (velodyne_decoder.h).
enum class DecodeResult {
  accepted,
  wrong_size,               // payload is not 1206 bytes
  unknown_product,          // product id byte is not a known Velodyne product
  unsupported_return_mode,  // not 0x37 / 0x38 / 0x39
  bad_block_flag,           // a block does not start with 0xFF 0xEE
  azimuth_out_of_range,     // a block azimuth >= 36000
  timestamp_out_of_range,   // timestamp >= one hour in microseconds
  dual_pair_mismatch,       // dual return: the two blocks of a pair carry different azimuths
};
std::string_view to_string(DecodeResult result);

// The name of a Velodyne product id byte ("HDL-32E", "VLP-16", ...); empty if unknown.
std::string_view product_name(std::uint8_t product_id);

// Parses and validates a packet without making points. `reference_ns` is any time within half an
// hour of the packet (e.g. its receive time): the packet's hour is the one that puts its timestamp
// nearest reference_ns, so packets on either side of the top of the hour resolve correctly. The first
// firing is the timestamp moved by the model's first_firing_after_timestamp_us. `out` is written only
// when the result is `accepted`.
DecodeResult parse_packet(const SensorModel& model, std::span<const std::uint8_t> payload,
                          TimeNs reference_ns, PacketReturns& out);

// The time of `ns_past_hour` in the hour that puts it nearest `reference_ns`.
TimeNs resolve_hour(TimeNs ns_past_hour, TimeNs reference_ns);

// A position packet (512 bytes): its timestamp and, when the sensor has a GPS receiver, the NMEA
// sentence it last received (bytes 206 on).
struct PositionPacket {
  std::uint32_t timestamp_us = 0;  // microseconds past the hour (< 3.6e9)
  std::string_view nmea;           // up to the first CR, LF or NUL; empty without a GPS receiver
};
// nullopt unless `payload` is 512 bytes with a timestamp below one hour.
std::optional<PositionPacket> parse_position_packet(std::span<const std::uint8_t> payload);

// A recommended-minimum NMEA sentence ($GPRMC, or another talker's RMC) with status A (valid) and an
// intact checksum: the UTC time it states, ns since 1970; nullopt otherwise.
std::optional<TimeNs> nmea_rmc_utc(std::string_view sentence);

}  // namespace rsu::lidar
