// SPDX-License-Identifier: Apache-2.0
#include "core/lidar_mount.h"

#include <cmath>

#include "common/angles.h"

namespace rsu::core {

LidarMount::LidarMount(const Pose3& sensor_to_map)
    : pose_(sensor_to_map),
      sensor_to_map_(sensor_to_map.to_isometry()),
      map_to_sensor_(sensor_to_map_.inverse()),
      xy_(sensor_to_map.x, sensor_to_map.y) {}

void LidarMount::to_map_frame(std::span<const lidar::LidarPoint> in,
                              std::vector<lidar::LidarPoint>& out) const {
  const Eigen::Matrix3f r = sensor_to_map_.linear().cast<float>();
  const Eigen::Vector3f t = sensor_to_map_.translation().cast<float>();
  out.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3f q = r * Eigen::Vector3f(in[i].x, in[i].y, in[i].z) + t;
    out[i] = in[i];
    out[i].x = q.x();
    out[i].y = q.y();
    out[i].z = q.z();
  }
}

double LidarMount::beam_azimuth(const Eigen::Vector2d& xy) const {
  const Eigen::Vector3d s = map_to_sensor_ * Eigen::Vector3d(xy.x(), xy.y(), pose_.z);
  // wrap_angle: -atan2(+0, -x) is -pi for a point straight behind, outside the promised (-pi, pi].
  return wrap_angle(-std::atan2(s.y(), s.x()));
}

}  // namespace rsu::core
