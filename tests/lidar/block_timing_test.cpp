// SPDX-License-Identifier: Apache-2.0
// block_duration_us, nominal_degrees_per_us and packet_timing (firing_schedule.h) against Velodyne's
// published timing, written out here from the manuals rather than taken from the library's tables:
//   VLP-16 (63-9243): a firing sequence of all 16 lasers every 55.296 us, two sequences per data block.
//   VLP-32C (63-9325): one 55.296 us sequence of 32 lasers per block.
//   HDL-32E (63-9113): one 46.08 us sequence of 32 lasers per block.
//   All spin at 600 rpm by default: 10 turns a second, 3600 deg/s, 0.0036 deg/us.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "lidar/firing_schedule.h"
#include "lidar/sensor_model.h"

namespace rsu::lidar {
namespace block_timing_test {

constexpr double kVlpSequenceUs = 55.296;
constexpr double kHdl32eSequenceUs = 46.08;

TEST(BlockTiming, BlockDurationIsSequencesPerBlockTimesTheSequence) {
  EXPECT_NEAR(block_duration_us(make_vlp16()), 2 * kVlpSequenceUs, 1e-12);  // 110.592 us
  EXPECT_NEAR(block_duration_us(make_vlp32c()), kVlpSequenceUs, 1e-12);
  EXPECT_NEAR(block_duration_us(make_hdl32e()), kHdl32eSequenceUs, 1e-12);
  SensorModel three = make_generic(8);
  three.sequences_per_block = 3;
  three.sequence_period_us = 40.0;
  EXPECT_NEAR(block_duration_us(three), 120.0, 1e-12);
}

// 360 deg x rpm / 60 per second, over 1e6 us.
TEST(BlockTiming, NominalRateIsTheRpmInDegreesPerMicrosecond) {
  EXPECT_NEAR(nominal_degrees_per_us(make_vlp16()), 0.0036, 1e-15);  // 600 rpm
  SensorModel fast = make_vlp32c();
  fast.rpm = 1200.0;
  EXPECT_NEAR(nominal_degrees_per_us(fast), 0.0072, 1e-15);
  fast.rpm = 300.0;
  EXPECT_NEAR(nominal_degrees_per_us(fast), 0.0018, 1e-15);
}

PacketBlocks stepped(std::uint16_t first_cdeg, int step_cdeg, TimeNs first_firing_ns) {
  PacketBlocks b;
  b.first_firing_ns = first_firing_ns;
  for (int k = 0; k < kBlocksPerPacket; ++k)
    b.azimuth_cdeg[static_cast<std::size_t>(k)] =
        static_cast<std::uint16_t>((first_cdeg + k * step_cdeg) % 36000);
  return b;
}

// A VLP-16 block lasts 110.592 us = 110592 ns; 12 of them 1327104 ns. Its azimuth steps by 0.40 deg
// (0.0036 deg/us x 110.592 us = 0.398, quantised): each block interpolates 0.40 deg, the last reuses it.
TEST(BlockTiming, RegularVlp16PacketStepsOneBlockAtATime) {
  const TimeNs t0 = 1'700'000'000'000'000'000;
  for (const std::uint16_t start : {std::uint16_t{0}, std::uint16_t{35900}}) {  // the second wraps
    const PacketTiming t = packet_timing(make_vlp16(), stepped(start, 40, t0), 0.0036);
    for (int k = 0; k < kBlocksPerPacket; ++k) {
      EXPECT_EQ(t.block_start_ns[static_cast<std::size_t>(k)], t0 + k * 110'592) << k;
      EXPECT_NEAR(t.diff_deg[static_cast<std::size_t>(k)], 0.40, 1e-12) << k;
    }
    EXPECT_EQ(t.end_ns, t0 + 1'327'104);
    EXPECT_FALSE(t.field_of_view_gap);
    EXPECT_NEAR(t.regular_turn_deg, 11 * 0.40, 1e-9);
    EXPECT_NEAR(t.regular_time_us, 11 * 110.592, 1e-9);
  }
}

// Dual return: blocks 2k and 2k + 1 are two echoes of one firing group: 6 groups a packet, each pair
// starting together, 110.592 us after the previous pair.
TEST(BlockTiming, DualReturnPairsShareTheirStart) {
  PacketBlocks b;
  b.dual_return = true;
  b.first_firing_ns = 5'000;
  for (int k = 0; k < kBlocksPerPacket; ++k)
    b.azimuth_cdeg[static_cast<std::size_t>(k)] = static_cast<std::uint16_t>(40 * (k / 2));
  const PacketTiming t = packet_timing(make_vlp16(), b, 0.0036);
  for (int k = 0; k < kBlocksPerPacket; ++k) {
    EXPECT_EQ(t.block_start_ns[static_cast<std::size_t>(k)], 5'000 + (k / 2) * 110'592) << k;
    EXPECT_NEAR(t.diff_deg[static_cast<std::size_t>(k)], 0.40, 1e-12) << k;
  }
  EXPECT_EQ(t.end_ns, 5'000 + 6 * 110'592);
  EXPECT_NEAR(t.regular_turn_deg, 5 * 0.40, 1e-9);
  EXPECT_NEAR(t.regular_time_us, 5 * 110.592, 1e-9);
}

// A VLP-32C with a limited field of view: blocks 0-5 at 0.00 .. 1.00 deg (0.20 deg apart), then the
// sensor stops firing and resumes 180 deg on (blocks 6-11 at 181.00 .. 182.00). 180 deg at 0.0036 deg/us
// is 50000 us: block 6 starts 50 ms after block 5. Block 5 (before the gap) reuses the regular 0.20.
TEST(BlockTiming, FieldOfViewGapIsTimedByTheRotationRate) {
  PacketBlocks b;
  b.first_firing_ns = 1'000'000;
  for (int k = 0; k < kBlocksPerPacket; ++k)
    b.azimuth_cdeg[static_cast<std::size_t>(k)] =
        static_cast<std::uint16_t>(k < 6 ? 20 * k : 20 * (k - 1) + 18000);
  const PacketTiming t = packet_timing(make_vlp32c(), b, 0.0036);
  EXPECT_TRUE(t.field_of_view_gap);
  for (int k = 0; k < 6; ++k)
    EXPECT_EQ(t.block_start_ns[static_cast<std::size_t>(k)], 1'000'000 + k * 55'296) << k;
  const TimeNs after_gap = 1'000'000 + 5 * 55'296 + 50'000'000;
  for (int k = 6; k < kBlocksPerPacket; ++k)
    EXPECT_EQ(t.block_start_ns[static_cast<std::size_t>(k)], after_gap + (k - 6) * 55'296) << k;
  for (int k = 0; k < kBlocksPerPacket; ++k)
    EXPECT_NEAR(t.diff_deg[static_cast<std::size_t>(k)], 0.20, 1e-12) << k;
  EXPECT_EQ(t.end_ns, after_gap + 6 * 55'296);
  // The regular steps: 5 before the gap, 5 after.
  EXPECT_NEAR(t.regular_turn_deg, 10 * 0.20, 1e-9);
  EXPECT_NEAR(t.regular_time_us, 10 * 55.296, 1e-9);
  // Twice the rate: the same gap in half the time (25 ms).
  const PacketTiming fast = packet_timing(make_vlp32c(), b, 0.0072);
  EXPECT_EQ(fast.block_start_ns[6], 1'000'000 + 5 * 55'296 + 25'000'000);
}

TEST(BlockTiming, RefusesARateThatIsNotPositiveOrAnUnusableModel) {
  const PacketBlocks b = stepped(0, 40, 0);
  for (const double rate :
       {0.0, -0.0036, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
    EXPECT_THROW(packet_timing(make_vlp16(), b, rate), std::invalid_argument) << rate;
  SensorModel broken = make_vlp16();
  broken.sequence_period_us = 0.0;
  EXPECT_THROW(packet_timing(broken, b, 0.0036), std::invalid_argument);
}

}  // namespace block_timing_test
}  // namespace rsu::lidar
