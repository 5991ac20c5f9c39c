// SPDX-License-Identifier: Apache-2.0
// When each laser fires and where it points, shared by the simulator (which casts the rays) and the
// packet decoder (which rebuilds them), so that a simulated point survives encode -> decode exactly up
// to the distance quantum.
//
// Firings are grouped as in a Velodyne packet: 12 data blocks per packet, each block holding
// `sequences_per_block` firing sequences. Each block carries the encoder azimuth at its first firing,
// quantised to 0.01 deg. In dual-return mode the blocks come in pairs (the last and the strongest echo
// of the same firings, equal azimuths): the packet then holds 6 firing groups, not 12.
//
// Timing. Group g starts one block duration after group g - 1, as the sensor fires without pause,
// except across a field-of-view gap: a sensor set to a limited field of view stops firing at its end
// and resumes when the rotor reaches its start, so consecutive groups of one packet can be 180 deg and
// 50 ms apart (a step larger than any rotation rate up to 1200 rpm explains, x 1.5). The group after
// such a gap fired when the rotor reached its azimuth: the time before it plus the gap over the
// measured rotation rate (PacketTiming).
//
// Azimuth. A laser's beam rotation angle is interpolated between its group's azimuth and the next
// group's, plus the laser's azimuth offset:
//   azimuth = group_az + diff * dt_az / block_duration + azimuth_offset[laser], wrapped to [0, 2 pi),
// where diff = (next group az - group az) mod 360 deg and dt_az is the laser's place in the block as
// the manufacturer's precision-azimuth rule puts it: its sequence's start plus
// azimuth_interpolation_us[laser] (the firing time, except on the VLP-32C: sensor_model.h). The last
// group of a packet, whose successor is in the next packet, and a group before a field-of-view gap
// reuse the nearest regular difference of the packet (the Velodyne manuals' precision-azimuth procedure
// reuses the previous one): nothing is interpolated across a gap.
//
// Channel mapping: channel = sequence * laser_count + laser. A VLP-16 block holds two sequences
// (channels 16..31 are the second, fired 55.296 us after the first); a VLP-32C block holds one.
// Generic models have no packet format but are grouped the same way with one sequence per block;
// with more than 32 lasers a "block" still holds one whole sequence and channel = laser (0..N-1),
// so such a block is wider than a Velodyne one.
//
// A Velodyne packet stamps its first firing (the HDL-32E: its end) in whole microseconds, so the
// schedule puts every packet's timestamp on the microsecond grid (its first firing within 0.5 us of
// t0 + k * period): decoding the packet then recovers every firing time to the nanosecond.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/time.h"
#include "lidar/sensor_model.h"

namespace rsu::lidar {

constexpr int kBlocksPerPacket = 12;
constexpr int kChannelsPerBlock = 32;

// The 12 blocks of one packet as the encoder reports them.
struct PacketBlocks {
  TimeNs first_firing_ns = 0;                                  // time of block 0's first firing
  std::array<std::uint16_t, kBlocksPerPacket> azimuth_cdeg{};  // encoder azimuth, 0.01 deg, [0, 36000)
  bool dual_return = false;  // blocks 2k and 2k + 1 hold two echoes of the same firings
};

// When each block of a packet fired and how far the rotor turned, by the rule of the file comment.
struct PacketTiming {
  std::array<TimeNs, kBlocksPerPacket> block_start_ns{};  // first firing of each block (pairs equal)
  std::array<double, kBlocksPerPacket> diff_deg{};        // azimuth difference each block interpolates
  TimeNs end_ns = 0;               // one block duration after the last group's start: the next packet's
  bool field_of_view_gap = false;  // the packet spans the gap of a limited field of view
  // The regular (gap-free) steps between consecutive groups: their azimuth sum and their duration,
  // from which a decoder measures the rotation rate.
  double regular_turn_deg = 0.0;
  double regular_time_us = 0.0;
};

// `degrees_per_us` is the rotation rate that times the group after a field-of-view gap (a decoder's
// measurement; the model's nominal rate when it has none). Throws std::invalid_argument when
// sensor_model_error(model) is not empty or the rate is not positive.
PacketTiming packet_timing(const SensorModel& model, const PacketBlocks& blocks, double degrees_per_us);
// The model's nominal rotation rate in degrees per microsecond.
double nominal_degrees_per_us(const SensorModel& model);

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

// The shared timing and interpolation rule (see the file comment), at the model's nominal rate. Used by
// FiringSchedule::firings and by the packet decoder. Channels beyond the model's lasers (a VLP-16 has
// 16 per sequence) are not listed. Throws std::invalid_argument when sensor_model_error(model) is not
// empty.
std::vector<Firing> beam_firings(const SensorModel& model, const PacketBlocks& blocks);
// The same for a packet whose timing is known, into `out` (cleared first), so that a decoder can reuse
// one buffer packet after packet.
void beam_firings(const SensorModel& model, const PacketBlocks& blocks, const PacketTiming& timing,
                  std::vector<Firing>& out);

// Duration of one data block: sequences_per_block firing sequences, in microseconds.
double block_duration_us(const SensorModel& model);

}  // namespace rsu::lidar
