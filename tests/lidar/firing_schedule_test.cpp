// SPDX-License-Identifier: Apache-2.0
#include "lidar/firing_schedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "common/angles.h"
#include "published_tables.h"

namespace rsu::lidar {
namespace {

// Signed smallest difference a - b in degrees.
double angle_diff_deg(double a_deg, double b_deg) {
  return std::remainder(a_deg - b_deg, 360.0);
}

// The true (continuous) encoder angle at time t: start + 360 deg * 10 Hz * elapsed.
double true_encoder_deg(double start_deg, TimeNs t0, TimeNs t) {
  return start_deg + 360.0 * 10.0 * static_cast<double>(t - t0) * 1e-9;
}

TEST(LidarFiringSchedule, PacketPeriods) {
  // 12 blocks x 2 sequences x 55.296 us and 12 blocks x 1 sequence.
  EXPECT_EQ(FiringSchedule(make_vlp16(), 0).packet_period_ns(), 1'327'104);
  EXPECT_EQ(FiringSchedule(make_vlp32c(), 0).packet_period_ns(), 663'552);
}

TEST(LidarFiringSchedule, PacketsPerSecond) {
  for (const auto& [model, expected_rate] : {std::pair{make_vlp16(), 754}, std::pair{make_vlp32c(), 1507}}) {
    const TimeNs t0 = 1'700'000'000'123'456'789;
    const FiringSchedule schedule(model, t0);
    // Count packets whose first firing falls within ten seconds.
    std::int64_t packets = 0;
    while (schedule.packet(packets).first_firing_ns < t0 + 10 * kNsPerSecond) {
      ++packets;
    }
    const double per_second = static_cast<double>(packets) / 10.0;
    EXPECT_EQ(std::lround(per_second), expected_rate) << model.name;
    const double exact = 1.0 / (12 * model.sequences_per_block * test::kSequenceUs * 1e-6);
    EXPECT_NEAR(per_second, exact, 0.11) << model.name;
  }
}

TEST(LidarFiringSchedule, FiringsInOneRotation) {
  // 0.1 s / 55.296 us = 1808.45 sequences per rotation at 600 rpm: each laser fires 1808 or 1809 times.
  const double sequences = 0.1 / (test::kSequenceUs * 1e-6);
  for (const SensorModel& model : {make_vlp16(), make_vlp32c()}) {
    const TimeNs t0 = 5 * kNsPerSecond + 321;
    const FiringSchedule schedule(model, t0, 42.0);
    std::vector<int> per_laser(model.laser_count(), 0);
    std::size_t total = 0;
    for (std::int64_t k = 0;; ++k) {
      const PacketBlocks blocks = schedule.packet(k);
      if (blocks.first_firing_ns >= t0 + kNsPerSecond / 10) {
        break;
      }
      for (const Firing& f : schedule.firings(blocks)) {
        if (f.time_ns >= t0 && f.time_ns < t0 + kNsPerSecond / 10) {
          ++per_laser[f.laser];
          ++total;
        }
      }
    }
    // A window of a perfectly periodic lattice holds floor or ceil of (length / period) points; packet
    // starts rounded to the microsecond can move one firing across either end.
    for (const int n : per_laser) {
      EXPECT_GE(n, static_cast<int>(std::floor(sequences)) - 1) << model.name;
      EXPECT_LE(n, static_cast<int>(std::ceil(sequences)) + 1) << model.name;
    }
    EXPECT_NEAR(static_cast<double>(total), sequences * static_cast<double>(model.laser_count()),
                2.0 * static_cast<double>(model.laser_count()))
        << model.name;
  }
}

TEST(LidarFiringSchedule, PacketStartsOnTheMicrosecondGrid) {
  const TimeNs t0 = 777'777'777;
  const FiringSchedule schedule(make_vlp16(), t0);
  for (std::int64_t k : {0, 1, 2, 3, 1000, -5}) {
    const TimeNs start = schedule.packet(k).first_firing_ns;
    EXPECT_EQ(start % 1000, 0);
    EXPECT_LE(std::abs(start - (t0 + k * 1'327'104)), 500);
  }
}

TEST(LidarFiringSchedule, Vlp16TimesAndChannels) {
  const FiringSchedule schedule(make_vlp16(), 1'000'000'000, 10.0);
  const PacketBlocks blocks = schedule.packet(3);
  const std::vector<Firing> firings = schedule.firings(blocks);
  ASSERT_EQ(firings.size(), 12U * 32U);
  for (std::size_t i = 0; i < firings.size(); ++i) {
    const Firing& f = firings[i];
    const int block = static_cast<int>(i / 32);
    const int channel = static_cast<int>(i % 32);
    const int sequence = channel / 16;
    const int laser = channel % 16;
    EXPECT_EQ(f.block, block);
    EXPECT_EQ(f.channel, channel);
    EXPECT_EQ(f.laser, laser);
    // block b at b * 110.592 us, second sequence 55.296 us later, laser i at i * 2.304 us.
    EXPECT_EQ(f.time_ns, blocks.first_firing_ns + block * 110'592 + sequence * 55'296 + laser * 2'304);
  }
}

TEST(LidarFiringSchedule, Vlp32cTimesFireInPairs) {
  const FiringSchedule schedule(make_vlp32c(), 0, 0.0);
  const PacketBlocks blocks = schedule.packet(0);
  const std::vector<Firing> firings = schedule.firings(blocks);
  ASSERT_EQ(firings.size(), 12U * 32U);
  for (std::size_t i = 0; i < firings.size(); ++i) {
    const int block = static_cast<int>(i / 32);
    const int laser = static_cast<int>(i % 32);
    EXPECT_EQ(firings[i].channel, laser);
    EXPECT_EQ(firings[i].time_ns, blocks.first_firing_ns + block * 55'296 + (laser / 2) * 2'304);
  }
}

TEST(LidarFiringSchedule, BlockAzimuthIsQuantisedEncoderAngle) {
  const TimeNs t0 = 123'456'789'000;
  const double start = 359.5;  // crosses 0 within the first packets
  const FiringSchedule schedule(make_vlp16(), t0, start);
  for (std::int64_t k = 0; k < 40; ++k) {
    const PacketBlocks blocks = schedule.packet(k);
    for (int b = 0; b < 12; ++b) {
      const TimeNs t = blocks.first_firing_ns + b * 110'592;
      double expected = std::fmod(true_encoder_deg(start, t0, t), 360.0);
      long cdeg = std::lround(expected * 100.0) % 36000;
      EXPECT_EQ(blocks.azimuth_cdeg[static_cast<std::size_t>(b)], cdeg) << "packet " << k << " block " << b;
    }
  }
}

TEST(LidarFiringSchedule, FiringAzimuthFollowsTheRotor) {
  // Ground truth: a beam's rotation angle is the rotor angle at its firing time minus the calibration
  // files' rot_correction (sensor_model.h), up to the block azimuth's rounding (0.005 deg) plus the
  // rounding of the difference it is interpolated with (0.01 deg, scaled by dt / block duration,
  // which is <= 1.25 for the VLP-32C's last pair). The VLP-32C manual's precision azimuth places the
  // pair fired k-th at 2k x 2.304 us of the block, not at its firing time k x 2.304 us.
  for (const SensorModel& model : {make_vlp16(), make_vlp32c()}) {
    const TimeNs t0 = 987'654'321;
    const double start = 358.0;
    const FiringSchedule schedule(model, t0, start);
    const bool vlp32c = model.name == "vlp32c";
    for (std::int64_t k = 0; k < 30; ++k) {
      for (const Firing& f : schedule.firings(schedule.packet(k))) {
        ASSERT_GE(f.azimuth_rad, 0.0);
        ASSERT_LT(f.azimuth_rad, 2.0 * std::numbers::pi);
        const double rot_correction = vlp32c ? test::kVlp32cRotCorrectionDeg[f.laser] : 0.0;
        const TimeNs pair_time_ns = vlp32c ? (f.laser / 2) * 2'304 : 0;  // the pair's firing, in the block
        const TimeNs azimuth_time = f.time_ns + pair_time_ns;            // VLP-32C: twice into the block
        const double expected = true_encoder_deg(start, t0, azimuth_time) - rot_correction;
        EXPECT_NEAR(angle_diff_deg(rad_to_deg(f.azimuth_rad), expected), 0.0, 0.0175 + 1e-9)
            << model.name << " packet " << k << " channel " << f.channel;
      }
    }
  }
}

TEST(LidarFiringSchedule, InterpolationRuleIncludingLastBlockAndWrap) {
  const SensorModel model = make_vlp16();
  PacketBlocks blocks;
  blocks.first_firing_ns = 0;
  // Uneven steps and a wrap through 36000 between blocks 4 and 5.
  const std::array<std::uint16_t, 12> az = {35800, 35840, 35879, 35920, 35980, 20,
                                            60,    99,    140,   180,   219,   260};
  blocks.azimuth_cdeg = az;
  const std::vector<Firing> firings = beam_firings(model, blocks);
  ASSERT_EQ(firings.size(), 384U);
  for (const Firing& f : firings) {
    const auto b = static_cast<std::size_t>(f.block);
    const std::size_t from = b < 11 ? b : 10;  // block 11 reuses block 10's difference
    const int next_diff = static_cast<int>(az[from + 1]) - static_cast<int>(az[from]);
    const int diff = (next_diff + 36000) % 36000;
    const double dt_us = (f.channel / 16) * 55.296 + (f.channel % 16) * 2.304;
    const double expected = az[b] / 100.0 + diff / 100.0 * dt_us / 110.592;
    EXPECT_NEAR(angle_diff_deg(rad_to_deg(f.azimuth_rad), expected), 0.0, 1e-9) << "block " << b;
  }
  // Block 11 reuses block 10's difference (0.41 deg): its last firing, 108.288 us into the block.
  EXPECT_NEAR(rad_to_deg(firings.back().azimuth_rad), 2.60 + 0.41 * (55.296 + 15 * 2.304) / 110.592, 1e-9);
}

TEST(LidarFiringSchedule, GenericModelMapsChannelsToLasers) {
  const SensorModel model = make_generic(64);
  const FiringSchedule schedule(model, 0);
  EXPECT_EQ(schedule.packet_period_ns(), 663'552);
  const PacketBlocks blocks = schedule.packet(1);
  const std::vector<Firing> firings = schedule.firings(blocks);
  ASSERT_EQ(firings.size(), 12U * 64U);
  for (std::size_t i = 0; i < firings.size(); ++i) {
    EXPECT_EQ(firings[i].channel, static_cast<int>(i % 64));
    EXPECT_EQ(firings[i].laser, i % 64);
    const TimeNs into_block = firings[i].time_ns - blocks.first_firing_ns - firings[i].block * 55'296;
    EXPECT_GE(into_block, 0);
    EXPECT_LT(into_block, 55'296);
  }
}

TEST(LidarFiringSchedule, RejectsInvalidModels) {
  SensorModel broken = make_vlp16();
  broken.elevation_deg.pop_back();
  EXPECT_THROW(FiringSchedule(broken, 0), std::invalid_argument);
  EXPECT_THROW((void)beam_firings(broken, PacketBlocks{}), std::invalid_argument);
  EXPECT_THROW(FiringSchedule(make_vlp16(), 0, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::lidar
