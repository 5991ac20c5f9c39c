// SPDX-License-Identifier: Apache-2.0
// Where the LiDAR stands: its surveyed pose in the map frame (sensor -> map), and what the RSU asks of
// it: points moved into the map frame, and the beam azimuth at which the sensor sees a place on the map.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "common/pose.h"
#include "lidar/point.h"

namespace rsu::core {

class LidarMount {
 public:
  explicit LidarMount(const Pose3& sensor_to_map);

  // `in` (sensor frame) moved into the map frame; ring, beam azimuth (the sensor's) and time are kept.
  void to_map_frame(std::span<const lidar::LidarPoint> in, std::vector<lidar::LidarPoint>& out) const;
  // The beam azimuth (LidarPoint::azimuth_rad: clockwise from the sensor's +x) of the map point `xy`
  // taken at the LiDAR's height, in (-pi, pi].
  double beam_azimuth(const Eigen::Vector2d& xy) const;

  const Pose3& pose() const { return pose_; }
  Eigen::Vector3d position() const { return sensor_to_map_.translation(); }
  const Eigen::Vector2d& xy() const { return xy_; }

 private:
  Pose3 pose_;
  Eigen::Isometry3d sensor_to_map_;
  Eigen::Isometry3d map_to_sensor_;
  Eigen::Vector2d xy_;
};

}  // namespace rsu::core
