// SPDX-License-Identifier: Apache-2.0
#include "perception/lidar_geometry.h"

#include <algorithm>
#include <cmath>

namespace rsu::perception {

bool LidarGeometry::sees_surface(double range_m, double low, double high) const {
  if (elevations_rad.empty())
    return true;
  if (!(range_m > 0.0))
    return false;
  const double h = height_above_ground();
  for (const double e : elevations_rad) {
    const double z = h + range_m * std::tan(e);  // where the laser's cone crosses that range
    if (z >= low && z <= high)
      return true;
  }
  return false;
}

bool LidarGeometry::occluded(const Eigen::Vector2d& xy, double margin) const {
  const Eigen::Vector2d sight = xy - this->xy();
  const double range = sight.norm();
  if (occluders.empty() || !(range > margin))
    return false;
  const double cos_max = std::cos(std::max(2.0 * azimuth_step_rad, std::atan(margin / range)));
  for (const Eigen::Vector2d& o : occluders) {
    const Eigen::Vector2d to = o - this->xy();
    const double r = to.norm();
    if (r > 0.0 && r < range - margin && to.dot(sight) >= cos_max * r * range)
      return true;
  }
  return false;
}

}  // namespace rsu::perception
