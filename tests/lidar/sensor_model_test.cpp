// SPDX-License-Identifier: Apache-2.0
#include "lidar/sensor_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "common/angles.h"
#include "published_tables.h"

namespace rsu::lidar {
namespace {

// Elevation asin(z) and clockwise azimuth atan2(-y, x) of the beam must be the published angles.
void expect_beam_angles(const SensorModel& m, std::size_t laser, double elevation_deg) {
  for (const double az_deg : {0.0, 37.5, 90.0, 179.9, 270.0, 359.0}) {
    const Eigen::Vector3d d = m.beam_direction(laser, deg_to_rad(az_deg));
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_NEAR(rad_to_deg(std::asin(d.z())), elevation_deg, 1e-9) << "laser " << laser;
    double measured_az = rad_to_deg(std::atan2(-d.y(), d.x()));
    if (measured_az < 0) {
      measured_az += 360.0;
    }
    EXPECT_NEAR(measured_az, az_deg, 1e-9) << "laser " << laser;
  }
}

TEST(LidarSensorModel, Vlp16MatchesPublishedTables) {
  const SensorModel m = make_vlp16();
  ASSERT_EQ(m.laser_count(), 16U);
  ASSERT_EQ(m.azimuth_offset_deg.size(), 16U);
  ASSERT_EQ(m.firing_offset_us.size(), 16U);
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_EQ(m.azimuth_offset_deg[i], 0.0);
    EXPECT_NEAR(m.firing_offset_us[i], static_cast<double>(i) * test::kFiringIntervalUs, 1e-9);
    expect_beam_angles(m, i, test::kVlp16ElevationDeg[i]);
  }
  EXPECT_EQ(m.sequences_per_block, 2);
  EXPECT_DOUBLE_EQ(m.sequence_period_us, test::kSequenceUs);
  EXPECT_DOUBLE_EQ(m.distance_unit_m, 0.002);
  EXPECT_DOUBLE_EQ(m.max_range_m, 100.0);
  EXPECT_GT(m.min_range_m, 0.0);
  EXPECT_EQ(m.product_id, 0x22);
  EXPECT_DOUBLE_EQ(m.rpm, 600.0);
  EXPECT_TRUE(sensor_model_error(m).empty()) << sensor_model_error(m);
}

TEST(LidarSensorModel, Vlp32cMatchesPublishedTables) {
  const SensorModel m = make_vlp32c();
  ASSERT_EQ(m.laser_count(), 32U);
  for (std::size_t i = 0; i < 32; ++i) {
    EXPECT_DOUBLE_EQ(m.azimuth_offset_deg[i], -test::kVlp32cRotCorrectionDeg[i]) << "laser " << i;
    EXPECT_NEAR(m.firing_offset_us[i], static_cast<double>(i / 2) * test::kFiringIntervalUs, 1e-9);
    // The manual's precision azimuth: channels K and K + 1 (K even) at K x 2.304 us of the gap.
    EXPECT_NEAR(m.azimuth_interpolation_us[i], static_cast<double>(i - i % 2) * test::kFiringIntervalUs,
                1e-9);
    expect_beam_angles(m, i, test::kVlp32cElevationDeg[i]);
  }
  EXPECT_EQ(m.sequences_per_block, 1);
  EXPECT_DOUBLE_EQ(m.distance_unit_m, 0.004);
  EXPECT_DOUBLE_EQ(m.max_range_m, 200.0);
  EXPECT_EQ(m.product_id, 0x28);
  EXPECT_TRUE(sensor_model_error(m).empty()) << sensor_model_error(m);
}

TEST(LidarSensorModel, BeamDirectionIsClockwiseFromForward) {
  const SensorModel m = make_vlp16();
  // Laser 1 is +1 deg. Azimuth 90 deg (clockwise seen from above) points to the right: -y.
  const Eigen::Vector3d right = m.beam_direction(1, deg_to_rad(90.0));
  EXPECT_NEAR(right.x(), 0.0, 1e-12);
  EXPECT_NEAR(right.y(), -std::cos(deg_to_rad(1.0)), 1e-12);
  EXPECT_NEAR(right.z(), std::sin(deg_to_rad(1.0)), 1e-12);
  EXPECT_THROW((void)m.beam_direction(16, 0.0), std::out_of_range);
}

TEST(LidarSensorModel, RotationFigures) {
  const SensorModel m = make_vlp16();
  EXPECT_NEAR(m.rotation_hz(), 10.0, 1e-12);
  EXPECT_NEAR(m.azimuth_step_deg(), 360.0 * 10.0 * 55.296e-6, 1e-12);  // ~0.199 deg
  EXPECT_NEAR(m.sequences_per_rotation(), 0.1 / 55.296e-6, 1e-9);      // ~1808.4
}

TEST(LidarSensorModel, GenericModelSpreadsRingsAndFirings) {
  const SensorModel m = make_generic(64);
  ASSERT_EQ(m.laser_count(), 64U);
  EXPECT_EQ(m.name, "generic64");
  EXPECT_FALSE(m.has_packet_format());
  EXPECT_NEAR(m.elevation_deg.front(), -25.0, 1e-12);
  EXPECT_NEAR(m.elevation_deg.back(), 15.0, 1e-12);
  for (std::size_t i = 1; i < 64; ++i) {
    EXPECT_NEAR(m.elevation_deg[i] - m.elevation_deg[i - 1], 40.0 / 63.0, 1e-9);
    EXPECT_GT(m.firing_offset_us[i], m.firing_offset_us[i - 1]);
  }
  EXPECT_GE(m.firing_offset_us.front(), 0.0);
  EXPECT_LE(m.firing_offset_us.back(), 50.0);
  EXPECT_DOUBLE_EQ(m.distance_unit_m, 0.004);
  EXPECT_DOUBLE_EQ(m.max_range_m, 200.0);
  EXPECT_TRUE(sensor_model_error(m).empty()) << sensor_model_error(m);
  EXPECT_THROW((void)make_generic(1), std::invalid_argument);
  EXPECT_THROW((void)make_generic(257), std::invalid_argument);
}

TEST(LidarSensorModel, ByName) {
  EXPECT_EQ(sensor_model_by_name("vlp16").value().product_id, 0x22);
  EXPECT_EQ(sensor_model_by_name("vlp32c").value().product_id, 0x28);
  EXPECT_EQ(sensor_model_by_name("generic64").value().laser_count(), 64U);
  EXPECT_EQ(sensor_model_by_name("generic128").value().laser_count(), 128U);
  EXPECT_EQ(sensor_model_by_name("generic2").value().laser_count(), 2U);
  EXPECT_EQ(sensor_model_by_name("generic256").value().laser_count(), 256U);
  for (const char* bad : {"", "vlp", "VLP16", "vlp16 ", "generic", "generic1", "generic257", "generic-4",
                          "generic64x", "genericx", "generic99999999999999999999"}) {
    EXPECT_FALSE(sensor_model_by_name(bad).has_value()) << bad;
  }
}

TEST(LidarSensorModel, ErrorNamesBrokenModels) {
  SensorModel m = make_vlp32c();
  m.azimuth_offset_deg.pop_back();
  EXPECT_FALSE(sensor_model_error(m).empty());
  m = make_vlp16();
  m.sequences_per_block = 1;  // 16 channels cannot fill a 32-channel block
  EXPECT_FALSE(sensor_model_error(m).empty());
  m = make_vlp16();
  m.rpm = std::nan("");
  EXPECT_FALSE(sensor_model_error(m).empty());
  m = make_vlp16();
  m.firing_offset_us[3] = 60.0;  // beyond the 55.296 us sequence
  EXPECT_FALSE(sensor_model_error(m).empty());
  EXPECT_FALSE(sensor_model_error(SensorModel{}).empty());
}

}  // namespace
}  // namespace rsu::lidar
