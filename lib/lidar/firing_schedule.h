// When each laser fires and where it points, shared by the simulator (which casts the rays) and the
// packet decoder (which rebuilds them), so that a simulated point survives encode -> decode exactly up
// to the distance quantum.
//
// Firings are grouped as in a Velodyne packet: 12 data blocks per packet, each block holding
// `sequences_per_block` firing sequences. Each block carries the encoder azimuth at its first firing,
// quantised to 0.01 deg. A laser's beam rotation angle is interpolated between its block's azimuth and
// the next block's (for the last block of a packet, the previous block's azimuth difference is reused,
// as the decoder cannot see the next packet), plus the laser's azimuth offset.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/time.h"
#include "lidar/sensor_model.h"

namespace rsu {

constexpr int kBlocksPerPacket = 12;
constexpr int kChannelsPerBlock = 32;

// The 12 blocks of one packet as the encoder reports them.
struct PacketBlocks {
  TimeNs first_firing_ns = 0;                                // time of block 0's first firing
  std::array<std::uint16_t, kBlocksPerPacket> azimuth_cdeg{};  // encoder azimuth, 0.01 deg, [0, 36000)
};

// One laser firing: which laser, when, and the beam's rotation angle.
struct Firing {
  int block = 0;           // 0..11 within the packet
  int channel = 0;         // 0..31 within the block (VLP-16: sequence * 16 + laser)
  std::uint16_t laser = 0; // ring
  TimeNs time_ns = 0;
  double azimuth_rad = 0;  // beam rotation angle incl. the laser's offset, [0, 2 pi)
};

// The packet-shaped schedule of a sensor spinning at constant rate. Packet k's first firing is at
// t0 + k * packet period, and the encoder azimuth at time t is start_azimuth + rotation since t0.
class FiringSchedule {
 public:
  FiringSchedule(const SensorModel& model, TimeNs t0, double start_azimuth_deg = 0.0);

  TimeNs packet_period_ns() const;  // 12 blocks (VLP-16: 1327.104 us; VLP-32C: 663.552 us)
  PacketBlocks packet(std::int64_t k) const;
  // Every firing of one packet in channel order, its azimuths computed by beam_firings().
  std::vector<Firing> firings(const PacketBlocks& blocks) const;
  const SensorModel& model() const { return model_; }

 private:
  SensorModel model_;
  TimeNs t0_;
  double start_azimuth_deg_;
};

// The shared interpolation rule (see the file comment). Used by FiringSchedule::firings and by the
// packet decoder. Channels beyond the model's lasers (a VLP-16 has 16 per sequence) are not listed.
std::vector<Firing> beam_firings(const SensorModel& model, const PacketBlocks& blocks);

}  // namespace rsu
