// SPDX-License-Identifier: Apache-2.0
// Where an Ouster pixel's return lies, from the sensor's metadata (the firmware user manuals'
// "Lidar Range to XYZ" and the Ouster SDK's XYZ lookup table).
//
// In Ouster's lidar frame (x towards the connector, z up), column m of W has the encoder angle
// theta_e = 2 pi (1 - m / W) (counter-clockwise from +x: the head turns clockwise seen from above),
// pixel row r has the altitude phi_r and the azimuth offset theta_a = -beam_azimuth_deg[r]; the beam
// points along d = (cos(theta_e + theta_a) cos phi, sin(theta_e + theta_a) cos phi, sin phi), starts at
// the beam origin b = (n_x cos theta_e, n_x sin theta_e, n_z) and the range r is measured from a point
// |n| behind it:  p_lidar = b + (r - |n|) d.  The metadata's lidar_to_sensor_transform takes p_lidar
// to Ouster's sensor frame (x away from the connector, y left, z up, origin at the centre of the
// base), which is the project's sensor frame convention (x forward, y left, z up).
//
// The beam's azimuth in the LidarPoint convention (clockwise seen from above, 0 at sensor +x) is
// 2 pi m / W + pi + beam_azimuth_deg[r] for the usual lidar_to_sensor rotation (180 deg about z):
// column 0 looks backwards (towards the connector), column W / 2 forwards.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "lidar/ouster/ouster_metadata.h"
#include "lidar/sensor_model.h"

namespace rsu::lidar::ouster {

class BeamGeometry {
 public:
  explicit BeamGeometry(const Metadata& metadata);

  // The return of pixel `row` of column `measurement_id` at `range_mm`, sensor frame, metres. The
  // caller keeps row < pixels_per_column and measurement_id < columns_per_frame.
  Eigen::Vector3d point(int row, int measurement_id, double range_mm) const;
  // The beam's direction in the sensor frame (unit vector).
  Eigen::Vector3d direction(int row, int measurement_id) const;
  // The beam's azimuth, clockwise seen from above from sensor +x, in [0, 2 pi).
  double azimuth_rad(int row, int measurement_id) const;
  // The lidar origin (where ranges are measured from, up to the beam offset) in the sensor frame, m.
  Eigen::Vector3d lidar_origin_m() const { return translation_mm_ * 1e-3; }

 private:
  Eigen::Vector3d lidar_direction(int row, int measurement_id) const;
  double azimuth_of_direction(int row, int measurement_id) const;

  std::vector<double> cos_encoder_, sin_encoder_;  // per column
  std::vector<double> cos_offset_, sin_offset_;    // per row: theta_a
  std::vector<double> cos_altitude_, sin_altitude_;
  // When lidar_to_sensor turns only about z (it commutes with the encoder's turn): each row's beam
  // azimuth at column 0; column m's is 2 pi m / W further clockwise. Empty otherwise (atan2 per point).
  std::vector<double> row_azimuth_rad_;
  int columns_ = 0;
  double beam_x_mm_ = 0.0;
  double beam_z_mm_ = 0.0;
  double beam_length_mm_ = 0.0;  // |n|: range measured from this far behind the beam origin
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d translation_mm_;
};

// The project's sensor model of this Ouster (rsu core: rotation rate, per-ring azimuth offsets):
// ring = pixel row, elevation = beam altitude, azimuth offset = beam_azimuth_deg (clockwise, added to
// the encoder azimuth), every pixel of a column firing at the column's time, one column per
// "sequence", distance unit 1 mm (8 mm for RNG15_RFL8_NIR8), the given minimum range, the maximum
// range the profile's range field can hold, no Velodyne packet format.
SensorModel sensor_model(const Metadata& metadata, double min_range_m);

// point, lidar_direction and azimuth_rad are defined here, not in the .cpp: they run for every pixel
// (5.2 M a second from a 128 x 2048 x 20 Hz stream).

inline Eigen::Vector3d BeamGeometry::lidar_direction(int row, int measurement_id) const {
  const auto r = static_cast<std::size_t>(row);
  const auto m = static_cast<std::size_t>(measurement_id);
  // cos and sin of theta_e + theta_a by the angle sum rule: no trigonometry per point.
  const double c = cos_encoder_[m] * cos_offset_[r] - sin_encoder_[m] * sin_offset_[r];
  const double s = sin_encoder_[m] * cos_offset_[r] + cos_encoder_[m] * sin_offset_[r];
  return {c * cos_altitude_[r], s * cos_altitude_[r], sin_altitude_[r]};
}

inline Eigen::Vector3d BeamGeometry::point(int row, int measurement_id, double range_mm) const {
  const auto m = static_cast<std::size_t>(measurement_id);
  const Eigen::Vector3d beam_origin(beam_x_mm_ * cos_encoder_[m], beam_x_mm_ * sin_encoder_[m], beam_z_mm_);
  const Eigen::Vector3d lidar =
      beam_origin + (range_mm - beam_length_mm_) * lidar_direction(row, measurement_id);
  return (rotation_ * lidar + translation_mm_) * 1e-3;
}

inline double BeamGeometry::azimuth_rad(int row, int measurement_id) const {
  if (row_azimuth_rad_.empty()) {
    return azimuth_of_direction(row, measurement_id);
  }
  return wrap_angle_positive(row_azimuth_rad_[static_cast<std::size_t>(row)] +
                             2.0 * kPi * measurement_id / columns_);
}

}  // namespace rsu::lidar::ouster
