// SPDX-License-Identifier: Apache-2.0
// Spinning-LiDAR sensor models (docs/design.md §2): beam geometry, firing timing and packet constants.
//
// Sensor frame: x forward, y left, z up. A beam with elevation w and rotation angle a (clockwise seen
// from above, 0 at +x, the Velodyne azimuth convention) points along
//   (cos w cos a, -cos w sin a, sin w).
// Laser i's beam rotation angle is the encoder azimuth where the manufacturer's precision-azimuth rule
// places it in its data block (azimuth_interpolation_us[i]; firing_schedule.h) plus azimuth_offset_deg[i].
//
// Sign convention of the azimuth offset: it is ADDED to the encoder azimuth, as the Velodyne manuals'
// azimuth offset (delta) is. The Velodyne calibration files (ROS velodyne driver, nebula, VeloView's
// rotCorrection) store the same angle with the opposite sign as `rot_correction`, which the drivers
// SUBTRACT from the block azimuth (VLP-32C manual 63-9325 sec. 9.5 says so); azimuth_offset_deg is
// therefore -rot_correction. A decoder that adds rot_correction misplaces every VLP-32C point by twice
// its offset (2.8 or 8.4 deg), which decoding a real capture against nebula's reference decode shows
// (tests/lidar/real_capture_test.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rsu::lidar {

struct SensorModel {
  std::string name;                        // "vlp16", "vlp32c", "generic64", ...
  std::vector<double> elevation_deg;       // per laser, channel (firing) order
  std::vector<double> azimuth_offset_deg;  // per laser, added to the encoder azimuth (-rot_correction)
  std::vector<double> firing_offset_us;    // per laser, from the start of its firing sequence
  // Per laser, from the start of its firing sequence: the time at which the block's azimuth gap is
  // interpolated for this laser (firing_schedule.h). Equal to firing_offset_us, except on the VLP-32C,
  // whose manual interpolates the pair fired k-th at 2k x 2.304 us (make_vlp32c).
  std::vector<double> azimuth_interpolation_us;
  double sequence_period_us = 55.296;  // one firing sequence of every laser
  int sequences_per_block = 1;         // data blocks per packet hold 32 channels: VLP-16 packs 2
  double distance_unit_m = 0.002;      // packet distance quantum
  double min_range_m = 0.5;
  double max_range_m = 100.0;
  std::uint8_t product_id = 0;  // packet byte 1205; 0 = no Velodyne packet format
  double rpm = 600.0;           // nominal; a decoder measures the real rate from the packets
  // The packet's first firing relative to its timestamp, microseconds: 0 where the timestamp is the
  // first firing (VLP-16, VLP-32C), negative where it is written at the end of the packet (HDL-32E).
  double first_firing_after_timestamp_us = 0.0;

  std::size_t laser_count() const { return elevation_deg.size(); }
  bool has_packet_format() const { return product_id != 0; }
  double rotation_hz() const { return rpm / 60.0; }
  // Encoder rotation during one firing sequence, degrees (about 0.199 at 600 rpm).
  double azimuth_step_deg() const { return 360.0 * rotation_hz() * sequence_period_us * 1e-6; }
  // Firing sequences in one rotation (about 1808.4 at 600 rpm; not an integer).
  double sequences_per_rotation() const { return 1e6 / (rotation_hz() * sequence_period_us); }
  // Unit beam direction in the sensor frame for laser `laser` at beam rotation angle `azimuth_rad`.
  Eigen::Vector3d beam_direction(std::size_t laser, double azimuth_rad) const;

  bool operator==(const SensorModel&) const = default;
};

// Why `model` cannot be used (tables of unequal length, non-positive periods, a packet format whose
// lasers x sequences_per_block is not 32, ...); empty when it is usable.
std::string sensor_model_error(const SensorModel& model);

SensorModel make_vlp16();
SensorModel make_vlp32c();
SensorModel make_hdl32e();
// A generic N-ring model for scaling tests: elevations evenly from -25 deg to +15 deg, every laser
// fires within one 55.296 us sequence, no packet format. Throws std::invalid_argument unless
// 2 <= rings <= 256.
SensorModel make_generic(int rings);

// "vlp16", "vlp32c", "hdl32e", "generic64", "generic128" (any "genericN" with 2 <= N <= 256); nullopt
// otherwise.
std::optional<SensorModel> sensor_model_by_name(std::string_view name);

}  // namespace rsu::lidar
