// SPDX-License-Identifier: Apache-2.0
// Ouster beam geometry (see ouster_geometry.h).
#include "lidar/ouster/ouster_geometry.h"

#include <cmath>

#include "common/angles.h"

namespace rsu::lidar::ouster {

BeamGeometry::BeamGeometry(const Metadata& metadata)
    : beam_x_mm_(metadata.beam_origin_x_mm),
      beam_z_mm_(metadata.beam_origin_z_mm),
      beam_length_mm_(std::hypot(metadata.beam_origin_x_mm, metadata.beam_origin_z_mm)),
      rotation_(metadata.lidar_to_sensor.topLeftCorner<3, 3>()),
      translation_mm_(metadata.lidar_to_sensor.topRightCorner<3, 1>()) {
  const int columns = metadata.columns_per_frame;
  for (int m = 0; m < columns; ++m) {
    const double encoder = 2.0 * kPi * (1.0 - static_cast<double>(m) / columns);
    cos_encoder_.push_back(std::cos(encoder));
    sin_encoder_.push_back(std::sin(encoder));
  }
  for (std::size_t r = 0; r < metadata.beam_altitude_deg.size(); ++r) {
    const double offset = -deg_to_rad(metadata.beam_azimuth_deg[r]);
    const double altitude = deg_to_rad(metadata.beam_altitude_deg[r]);
    cos_offset_.push_back(std::cos(offset));
    sin_offset_.push_back(std::sin(offset));
    cos_altitude_.push_back(std::cos(altitude));
    sin_altitude_.push_back(std::sin(altitude));
  }
  columns_ = columns;
  const bool about_z = rotation_.row(2).isApprox(Eigen::RowVector3d(0, 0, 1)) &&
                       rotation_.col(2).isApprox(Eigen::Vector3d(0, 0, 1));
  for (std::size_t r = 0; about_z && r < cos_altitude_.size(); ++r) {
    const Eigen::Vector3d d = direction(static_cast<int>(r), 0);
    row_azimuth_rad_.push_back(std::atan2(-d.y(), d.x()));
  }
}

Eigen::Vector3d BeamGeometry::direction(int row, int measurement_id) const {
  return rotation_ * lidar_direction(row, measurement_id);
}

double BeamGeometry::azimuth_of_direction(int row, int measurement_id) const {
  const Eigen::Vector3d d = direction(row, measurement_id);
  return wrap_angle_positive(std::atan2(-d.y(), d.x()));  // clockwise: y is left
}

SensorModel sensor_model(const Metadata& metadata, double min_range_m) {
  SensorModel s;
  s.name = metadata.model_name();
  s.elevation_deg = metadata.beam_altitude_deg;
  s.azimuth_offset_deg = metadata.beam_azimuth_deg;
  s.firing_offset_us.assign(metadata.beam_altitude_deg.size(), 0.0);
  s.azimuth_interpolation_us = s.firing_offset_us;  // every pixel of a column at the column's angle
  s.rpm = 60.0 * metadata.frequency_hz;
  s.sequence_period_us = 1e6 / (metadata.frequency_hz * static_cast<double>(metadata.columns_per_frame));
  s.sequences_per_block = 1;
  s.product_id = 0;
  // The largest range each profile's field holds (20, 19, or 15 bits of 8 mm).
  switch (metadata.profile) {
    case UdpProfile::legacy:
      s.distance_unit_m = 0.001;
      s.max_range_m = 0xFFFFF * 1e-3;
      break;
    case UdpProfile::rng19_rfl8_sig16_nir16:
      s.distance_unit_m = 0.001;
      s.max_range_m = 0x7FFFF * 1e-3;
      break;
    case UdpProfile::rng15_rfl8_nir8:
      s.distance_unit_m = 0.008;
      s.max_range_m = 0x7FFF * 8e-3;
      break;
  }
  s.min_range_m = min_range_m;
  return s;
}

}  // namespace rsu::lidar::ouster
