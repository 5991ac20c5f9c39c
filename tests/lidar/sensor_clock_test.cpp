// SPDX-License-Identifier: Apache-2.0
// The sensor clock offset (lidar/sensor_clock.h) against offsets and delays the test sets.
#include "lidar/sensor_clock.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace rsu::lidar {
namespace {

constexpr TimeNs kPacketPeriod = 663'552;  // a VLP-32C packet

TEST(SensorClock, EstimateIsTheOffsetPlusTheSmallestDelay) {
  SensorClock clock;
  EXPECT_FALSE(clock.offset_ns().has_value());
  const TimeNs offset = 52'312 * kNsPerMs;  // the sensor 52.312 s behind the host
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<TimeNs> delay(200'000, 3'000'000);  // 0.2 to 3 ms transit and queueing
  for (int k = 0; k < 2000; ++k) {
    const TimeNs sensor_end = 1'000 * kNsPerSecond + k * kPacketPeriod;
    clock.observe(sensor_end, sensor_end + offset + delay(rng));
  }
  ASSERT_TRUE(clock.offset_ns().has_value());
  EXPECT_GE(*clock.offset_ns(), offset + 200'000);
  EXPECT_LE(*clock.offset_ns(), offset + 250'000);
  EXPECT_EQ(clock.steps(), 0U);
}

// A host that falls behind raises the raw value, not the estimate; a drifting sensor clock is followed.
TEST(SensorClock, LagIsNotOffsetButDriftIs) {
  SensorClock clock;
  TimeNs sensor_end = 0;
  for (int k = 0; k < 100; ++k, sensor_end += kPacketPeriod)
    clock.observe(sensor_end, sensor_end + 1'000'000);
  for (int k = 0; k < 300; ++k, sensor_end += kPacketPeriod)  // 0.2 s of firings, the lag growing to 150 ms
    clock.observe(sensor_end, sensor_end + 1'000'000 + k * 500'000);
  EXPECT_LE(*clock.offset_ns(), 1'000'000 + 40'000);  // at most 100 ppm of the 0.35 s that passed
  EXPECT_GT(clock.last_raw_ns() - *clock.offset_ns(), 140 * kNsPerMs);
  // The sensor's clock runs 50 ppm slow for 100 s: the estimate follows the growing offset.
  SensorClock drifting;
  for (int k = 0; k < 150'000; ++k) {
    const TimeNs host = k * kPacketPeriod;
    const TimeNs sensor = host - static_cast<TimeNs>(static_cast<double>(host) * 50e-6);
    drifting.observe(sensor, host + 1'000'000);
  }
  const TimeNs drift = static_cast<TimeNs>(static_cast<double>(149'999 * kPacketPeriod) * 50e-6);  // ~5 ms
  EXPECT_NEAR(static_cast<double>(*drifting.offset_ns()), static_cast<double>(drift + 1'000'000), 100'000.0);
}

// The stamping offset never jumps: a packet that came through faster than all before lowers the
// estimate at once, the stamps follow at 1 % of the time passing, so packets stay in order.
TEST(SensorClock, StampingOffsetSlewsWithoutJumps) {
  SensorClock clock;
  TimeNs sensor_end = 0;
  clock.observe(sensor_end, sensor_end + 20 * kNsPerMs);  // the first packet waited 20 ms
  TimeNs previous_stamp = sensor_end + clock.stamping_offset_ns();
  for (int k = 1; k < 4000; ++k) {
    sensor_end += kPacketPeriod;
    clock.observe(sensor_end, sensor_end + kNsPerMs);  // the rest 1 ms
    const TimeNs stamp = sensor_end + clock.stamping_offset_ns();
    ASSERT_GE(stamp - previous_stamp, static_cast<TimeNs>(0.99 * static_cast<double>(kPacketPeriod)) - 1)
        << k;
    previous_stamp = stamp;
  }
  EXPECT_EQ(*clock.offset_ns(), kNsPerMs);
  EXPECT_EQ(clock.stamping_offset_ns(), kNsPerMs);  // 19 ms made up within 1.9 s of sensor time
}

TEST(SensorClock, AClockStepStartsAfresh) {
  SensorClock clock;
  clock.observe(10 * kNsPerSecond, 10 * kNsPerSecond + kNsPerMs);
  clock.observe(10 * kNsPerSecond + kPacketPeriod, 10 * kNsPerSecond + kPacketPeriod + kNsPerMs);
  // The sensor's clock set back by an hour: a new offset, not a lag of an hour.
  clock.observe(10 * kNsPerSecond - 3600 * kNsPerSecond, 10 * kNsPerSecond + 2 * kPacketPeriod + kNsPerMs);
  EXPECT_EQ(clock.steps(), 1U);
  EXPECT_NEAR(static_cast<double>(*clock.offset_ns()),
              static_cast<double>(3600 * kNsPerSecond + 2 * kPacketPeriod + kNsPerMs), 1.0);
  EXPECT_THROW(SensorClock(SensorClockConfig{.max_drift = -1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::lidar
