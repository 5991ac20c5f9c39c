// The Velodyne VLP-16 / VLP-32C data packet (DESIGN.md §2): the 1206-byte UDP payload on port 2368.
//
//   12 data blocks of 100 bytes: 0xFF 0xEE, azimuth uint16 LE (0.01 deg),
//                                32 x {distance uint16 LE (distance units), reflectivity uint8}
//   byte 1200: timestamp uint32 LE, microseconds past the top of the hour of the packet's first firing
//   byte 1204: return mode (0x37 strongest, 0x38 last, 0x39 dual)
//   byte 1205: product id (0x22 VLP-16, 0x28 VLP-32C)
// A distance of 0 means no return. Beam angles and firing times come from beam_firings()
// (firing_schedule.h), the rule shared with the simulator.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/time.h"
#include "lidar/firing_schedule.h"
#include "lidar/point.h"
#include "lidar/sensor_model.h"

namespace rsu {

constexpr std::size_t kPacketBytes = 1206;
constexpr std::size_t kBlockBytes = 100;
constexpr std::size_t kTimestampOffset = 1200;
constexpr std::size_t kReturnModeOffset = 1204;
constexpr std::size_t kProductIdOffset = 1205;
constexpr std::uint8_t kReturnStrongest = 0x37;
constexpr std::uint8_t kReturnLast = 0x38;
constexpr std::uint8_t kReturnDual = 0x39;
constexpr std::uint16_t kVelodyneDataPort = 2368;

// The content of one packet, channel by channel (channel numbering as in firing_schedule.h).
struct PacketReturns {
  PacketBlocks blocks;
  std::array<std::array<std::uint16_t, kChannelsPerBlock>, kBlocksPerPacket> distance_raw{};  // 0 = none
  std::array<std::array<std::uint8_t, kChannelsPerBlock>, kBlocksPerPacket> reflectivity{};
  std::uint8_t return_mode = kReturnStrongest;
};

// Range in metres -> packet distance units, rounded to nearest; 0 (no return) outside
// [min_range_m, max_range_m] or for NaN.
std::uint16_t quantize_distance(const SensorModel& model, double range_m);

// Writes the packet. The timestamp is first_firing_ns modulo one hour, in whole microseconds
// (floored). Throws std::invalid_argument if the model has no packet format or is invalid.
void encode_packet(const SensorModel& model, const PacketReturns& returns,
                   std::span<std::uint8_t, kPacketBytes> out);

// Why a packet was accepted or rejected. Checks run in this order and the first failure is reported:
// size, product id, return mode, block flags, block azimuths, timestamp.
enum class DecodeResult {
  accepted,
  wrong_size,               // payload is not 1206 bytes
  unknown_product,          // product id byte is not a known Velodyne product
  product_mismatch,         // a known product, but not the configured sensor
  unsupported_return_mode,  // not 0x37 / 0x38 (dual return 0x39 is not supported yet)
  bad_block_flag,           // a block does not start with 0xFF 0xEE
  azimuth_out_of_range,     // a block azimuth >= 36000
  timestamp_out_of_range,   // timestamp >= one hour in microseconds
};
std::string_view to_string(DecodeResult result);

struct DecodeStats {
  std::uint64_t accepted = 0;
  std::uint64_t wrong_size = 0;
  std::uint64_t unknown_product = 0;
  std::uint64_t product_mismatch = 0;
  std::uint64_t unsupported_return_mode = 0;
  std::uint64_t bad_block_flag = 0;
  std::uint64_t azimuth_out_of_range = 0;
  std::uint64_t timestamp_out_of_range = 0;
  std::uint64_t points_decoded = 0;  // returns appended as points
  std::uint64_t no_return = 0;       // firings with distance 0

  std::uint64_t packets() const;  // all packets seen, accepted or not
  std::uint64_t rejected() const { return packets() - accepted; }
};

// Parses and validates a packet without making points. `reference_ns` is any time within half an
// hour of the packet (e.g. its receive time): the packet's hour is the one that puts its timestamp
// nearest reference_ns, so packets on either side of the top of the hour resolve correctly.
// `out` is written only when the result is `accepted`.
DecodeResult parse_packet(const SensorModel& model, std::span<const std::uint8_t> payload,
                          TimeNs reference_ns, PacketReturns& out);

// Turns packets of one configured sensor into points. Never throws on packet content; a packet with
// any structural error is rejected whole and counted.
class PacketDecoder {
 public:
  // Throws std::invalid_argument if the model has no packet format or is invalid.
  explicit PacketDecoder(const SensorModel& model);

  // Appends the packet's returns to `out` (nothing on rejection): xyz in the sensor frame from the
  // range and beam_firings()' azimuth and the laser's elevation, time of the firing, ring = laser,
  // intensity = reflectivity.
  DecodeResult decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                      std::vector<LidarPoint>& out);

  const DecodeStats& stats() const { return stats_; }
  const SensorModel& model() const { return model_; }
  // The first firing time of the last accepted packet: its place in the stream (packet_order.h).
  TimeNs last_first_firing_ns() const { return returns_.blocks.first_firing_ns; }

 private:
  void count(DecodeResult result);

  SensorModel model_;
  std::vector<double> cos_elevation_;  // per laser, precomputed once
  std::vector<double> sin_elevation_;
  DecodeStats stats_;
  PacketReturns returns_;        // scratch, reused packet after packet
  std::vector<Firing> firings_;  // scratch
};

}  // namespace rsu
