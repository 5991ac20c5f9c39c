// When each laser fires and where it points, shared by the simulator (which casts the rays) and the
// packet decoder (which rebuilds them), so that a simulated point survives encode -> decode exactly up
// to the distance quantum.
//
// Firings are grouped as in a Velodyne packet: 12 data blocks per packet, each block holding
// `sequences_per_block` firing sequences. Each block carries the encoder azimuth at its first firing,
// quantised to 0.01 deg. A laser's beam rotation angle is interpolated between its block's azimuth and
// the next block's (for the last block of a packet, the previous block's azimuth difference is reused,
// as the decoder cannot see the next packet), plus the laser's azimuth offset:
//   azimuth = block_az + diff * dt_az / block_duration + azimuth_offset[laser], wrapped to [0, 2 pi),
// where diff = (next block az - block az) mod 360 deg and dt_az is the laser's place in the block as
// the manufacturer's precision-azimuth rule puts it: its sequence's start plus
// azimuth_interpolation_us[laser] (the firing time, except on the VLP-32C: sensor_model.h).
//
// Channel mapping: channel = sequence * laser_count + laser. A VLP-16 block holds two sequences
// (channels 16..31 are the second, fired 55.296 us after the first); a VLP-32C block holds one.
// Generic models have no packet format but are grouped the same way with one sequence per block;
// with more than 32 lasers a "block" still holds one whole sequence and channel = laser (0..N-1),
// so such a block is wider than a Velodyne one.
//
// A Velodyne packet stamps its first firing in whole microseconds, so the schedule puts every
// packet's first firing on the microsecond grid (within 0.5 us of t0 + k * period): decoding the
// packet then recovers every firing time to the nanosecond.
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
  TimeNs first_firing_ns = 0;                                  // time of block 0's first firing
  std::array<std::uint16_t, kBlocksPerPacket> azimuth_cdeg{};  // encoder azimuth, 0.01 deg, [0, 36000)
};

// One laser firing: which laser, when, and the beam's rotation angle.
struct Firing {
  int block = 0;            // 0..11 within the packet
  int channel = 0;          // within the block: sequence * laser_count + laser (see file comment)
  std::uint16_t laser = 0;  // ring
  TimeNs time_ns = 0;
  double azimuth_rad = 0;  // beam rotation angle incl. the laser's offset, [0, 2 pi)
};

// The packet-shaped schedule of a sensor spinning at constant rate. Packet k's first firing is at
// t0 + k * packet period (rounded to the microsecond), and the encoder azimuth at time t is
// start_azimuth + 360 * rotation_hz * (t - t0), wrapped to [0, 360) and quantised to 0.01 deg.
class FiringSchedule {
 public:
  // Throws std::invalid_argument when sensor_model_error(model) is not empty.
  FiringSchedule(const SensorModel& model, TimeNs t0, double start_azimuth_deg = 0.0);

  TimeNs packet_period_ns() const;  // 12 blocks (VLP-16: 1327.104 us; VLP-32C: 663.552 us)
  PacketBlocks packet(std::int64_t k) const;
  // Every firing of one packet in channel order, its azimuths computed by beam_firings().
  std::vector<Firing> firings(const PacketBlocks& blocks) const;
  // Encoder azimuth at time t, 0.01 deg in [0, 36000).
  std::uint16_t encoder_azimuth_cdeg(TimeNs t) const;
  const SensorModel& model() const { return model_; }

 private:
  SensorModel model_;
  TimeNs t0_;
  double start_azimuth_deg_;
};

// The shared interpolation rule (see the file comment). Used by FiringSchedule::firings and by the
// packet decoder. Channels beyond the model's lasers (a VLP-16 has 16 per sequence) are not listed.
// Throws std::invalid_argument when sensor_model_error(model) is not empty.
std::vector<Firing> beam_firings(const SensorModel& model, const PacketBlocks& blocks);
// The same, into `out` (cleared first), so that a decoder can reuse one buffer packet after packet.
void beam_firings(const SensorModel& model, const PacketBlocks& blocks, std::vector<Firing>& out);

// Duration of one data block: sequences_per_block firing sequences, in microseconds.
double block_duration_us(const SensorModel& model);

}  // namespace rsu
