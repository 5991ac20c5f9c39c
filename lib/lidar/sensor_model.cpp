// SPDX-License-Identifier: Apache-2.0
// Sensor tables from docs/design.md §2 (the manufacturers' manuals and the public Velodyne driver's
// calibration files).
#include "lidar/sensor_model.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::lidar {
namespace {

// Both sensors fire one laser (VLP-16) or one pair (VLP-32C) every 2.304 us (docs/design.md §2).
constexpr double kFiringIntervalUs = 2.304;
constexpr double kVelodyneSequenceUs = 55.296;

// The packet-format constants every Velodyne model sets. No manual gives a minimum range for the
// VLP-32C or the HDL-32E; 1.0 m, as for the VLP-16 (below), is an assumption for them: it only bounds
// what the simulator reports, the decoder keeps every return.
void set_packet_format(SensorModel& m, double sequence_us, int sequences_per_block, double distance_unit_m,
                       double max_range_m, std::uint8_t product_id) {
  m.sequence_period_us = sequence_us;
  m.sequences_per_block = sequences_per_block;
  m.distance_unit_m = distance_unit_m;
  m.min_range_m = 1.0;
  m.max_range_m = max_range_m;
  m.product_id = product_id;
  m.rpm = 600.0;
}

}  // namespace

Eigen::Vector3d SensorModel::beam_direction(std::size_t laser, double azimuth_rad) const {
  // .at(): a bad laser index from a caller is a clear error, not a read past the table.
  const double w = deg_to_rad(elevation_deg.at(laser));
  const double cos_w = std::cos(w);
  // Velodyne azimuth is clockwise seen from above, hence the minus sign on y (x forward, y left).
  return {cos_w * std::cos(azimuth_rad), -cos_w * std::sin(azimuth_rad), std::sin(w)};
}

std::string sensor_model_error(const SensorModel& model) {
  const std::size_t n = model.laser_count();
  if (n == 0) {
    return "sensor model '" + model.name + "' has no lasers";
  }
  if (model.azimuth_offset_deg.size() != n || model.firing_offset_us.size() != n ||
      model.azimuth_interpolation_us.size() != n) {
    return "sensor model '" + model.name +
           "': elevation, azimuth offset, firing offset and azimuth interpolation tables differ in length";
  }
  if (!(model.sequence_period_us > 0.0) || !std::isfinite(model.sequence_period_us)) {
    return "sensor model '" + model.name + "': sequence period must be positive";
  }
  if (model.sequences_per_block < 1) {
    return "sensor model '" + model.name + "': sequences_per_block must be at least 1";
  }
  if (!(model.rpm > 0.0) || !std::isfinite(model.rpm)) {
    return "sensor model '" + model.name + "': rpm must be positive";
  }
  if (!std::isfinite(model.first_firing_after_timestamp_us)) {
    return "sensor model '" + model.name + "': the timestamp's place in the packet must be finite";
  }
  if (!(model.distance_unit_m > 0.0) || !std::isfinite(model.distance_unit_m)) {
    return "sensor model '" + model.name + "': distance unit must be positive";
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(model.elevation_deg[i]) || !std::isfinite(model.azimuth_offset_deg[i]) ||
        !std::isfinite(model.firing_offset_us[i]) || model.firing_offset_us[i] < 0.0 ||
        model.firing_offset_us[i] >= model.sequence_period_us ||
        !std::isfinite(model.azimuth_interpolation_us[i]) || model.azimuth_interpolation_us[i] < 0.0) {
      return "sensor model '" + model.name + "': laser " + std::to_string(i) +
             " has a non-finite angle or a firing offset outside its sequence";
    }
  }
  // A Velodyne data block has 32 channels; the firing sequences of one block must fill them exactly.
  if (model.has_packet_format() &&
      n * static_cast<std::size_t>(model.sequences_per_block) != static_cast<std::size_t>(32)) {
    return "sensor model '" + model.name + "': lasers x sequences_per_block must be 32 for a packet format";
  }
  return {};
}

SensorModel make_vlp16() {
  SensorModel m;
  m.name = "vlp16";
  m.elevation_deg = {-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};
  m.azimuth_offset_deg.assign(16, 0.0);
  for (int i = 0; i < 16; ++i) {
    m.firing_offset_us.push_back(i * kFiringIntervalUs);
  }
  m.azimuth_interpolation_us = m.firing_offset_us;
  // 16 lasers x 2 sequences fill the 32 channels of a data block. The VLP-16 manual (63-9243, p. 3 of
  // early revisions) quotes a range "from 1 m to 100 m", and users of the ROS velodyne driver saw no
  // returns below about 0.9 m (ros-drivers/velodyne#60).
  set_packet_format(m, kVelodyneSequenceUs, 2, 0.002, 100.0, 0x22);
  return m;
}

SensorModel make_vlp32c() {
  SensorModel m;
  m.name = "vlp32c";
  m.elevation_deg = {-25,    -1,     -1.667, -15.639, -11.31, 0,      -0.667, -8.843, -7.254, 0.333,  -0.333,
                     -6.148, -5.333, 1.333,  0.667,   -4,     -4.667, 1.667,  1,      -3.667, -3.333, 3.333,
                     2.333,  -2.667, -3,     7,       4.667,  -2.333, -2,     15,     10.333, -1.333};
  // The manual's azimuth offsets (Table 9-6), i.e. the negated rot_correction of the Velodyne
  // calibration files (VLP32.yaml of the ROS / nebula drivers): see the sign note in sensor_model.h.
  m.azimuth_offset_deg = {1.4,  -4.2, 1.4,  -1.4, 1.4,  -1.4, 4.2,  -1.4, 1.4,  -4.2, 1.4,
                          -1.4, 4.2,  -1.4, 4.2,  -1.4, 1.4,  -4.2, 1.4,  -4.2, 4.2,  -1.4,
                          1.4,  -1.4, 1.4,  -1.4, 1.4,  -4.2, 4.2,  -1.4, 1.4,  -1.4};
  for (int i = 0; i < 32; ++i) {
    m.firing_offset_us.push_back((i / 2) * kFiringIntervalUs);  // lasers fire in pairs
    // The manual's precision-azimuth pseudo code (63-9325 sec. 9.5) interpolates the pair of channels
    // K, K + 1 (K even) at K x 2.304 us of the block's azimuth gap: twice the pair's firing time. The
    // reference decoder (nebula, Autoware's driver) does the same; decoding the real capture in
    // tests/data/real with the firing time instead leaves 1.3 % of nebula's points without one of
    // ours within 2 cm (beyond 10 m), with the manual's rule 0.4 %.
    m.azimuth_interpolation_us.push_back((i - i % 2) * kFiringIntervalUs);
  }
  set_packet_format(m, kVelodyneSequenceUs, 1, 0.004, 200.0, 0x28);
  return m;
}

SensorModel make_hdl32e() {
  SensorModel m;
  m.name = "hdl32e";
  // HDL-32E user manual (63-9113), "Laser Firing Sequence" and "Vertical angle" in firing order; the
  // same as the drivers' factory calibration file (HDL32.yaml: vert_correction, rot_correction 0).
  m.elevation_deg = {-30.67, -9.33,  -29.33, -8.00,  -28.00, -6.67,  -26.67, -5.33,  -25.33, -4.00,  -24.00,
                     -2.67,  -22.67, -1.33,  -21.33, 0.00,   -20.00, 1.33,   -18.67, 2.67,   -17.33, 4.00,
                     -16.00, 5.33,   -14.67, 6.67,   -13.33, 8.00,   -12.00, 9.33,   -10.67, 10.67};
  m.azimuth_offset_deg.assign(32, 0.0);
  // One laser at a time every 1.152 us, a sequence of all 32 every 46.08 us, one sequence per block.
  for (int i = 0; i < 32; ++i) {
    m.firing_offset_us.push_back(i * 1.152);
  }
  m.azimuth_interpolation_us = m.firing_offset_us;
  set_packet_format(m, 46.08, 1, 0.002, 100.0, 0x21);  // the manual quotes 80-100 m
  // The manual's Ethernet transit timing: the timestamp is written at the end of the packet; a point's
  // time is timestamp - 542.592 + block x 46.08 + laser x 1.152 us.
  m.first_firing_after_timestamp_us = -542.592;
  return m;
}

SensorModel make_generic(int rings) {
  if (rings < 2 || rings > 256) {
    throw std::invalid_argument("make_generic: rings must be in [2, 256], got " + std::to_string(rings));
  }
  SensorModel m;
  m.name = "generic" + std::to_string(rings);
  // Every laser fires within one 55.296 us sequence, evenly over its first ~50 us.
  const double firing_spacing_us = 50.0 / rings;
  for (int i = 0; i < rings; ++i) {
    m.elevation_deg.push_back(-25.0 + 40.0 * i / (rings - 1));
    m.azimuth_offset_deg.push_back(0.0);
    m.firing_offset_us.push_back(i * firing_spacing_us);
    m.azimuth_interpolation_us.push_back(i * firing_spacing_us);
  }
  m.sequence_period_us = kVelodyneSequenceUs;
  m.sequences_per_block = 1;
  m.distance_unit_m = 0.004;
  m.min_range_m = 0.5;
  m.max_range_m = 200.0;
  m.product_id = 0;  // no packet format
  m.rpm = 600.0;
  return m;
}

std::optional<SensorModel> sensor_model_by_name(std::string_view name) {
  if (name == "vlp16") {
    return make_vlp16();
  }
  if (name == "vlp32c") {
    return make_vlp32c();
  }
  if (name == "hdl32e") {
    return make_hdl32e();
  }
  constexpr std::string_view kGeneric = "generic";
  if (name.starts_with(kGeneric)) {
    const std::string_view digits = name.substr(kGeneric.size());
    int rings = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), rings);
    // Whole suffix must be digits (from_chars also accepts a leading '-', rejected by the range).
    if (ec == std::errc() && end == digits.data() + digits.size() && !digits.empty() && digits[0] != '-' &&
        rings >= 2 && rings <= 256) {
      return make_generic(rings);
    }
  }
  return std::nullopt;
}

}  // namespace rsu::lidar
