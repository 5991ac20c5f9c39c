// SPDX-License-Identifier: Apache-2.0
#include "perception/lidar_geometry.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

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

namespace {

bool occluded_by(std::span<const Eigen::Vector2d> occluders, const LidarGeometry& lidar,
                 const Eigen::Vector2d& xy, double margin) {
  const Eigen::Vector2d sight = xy - lidar.xy();
  const double range = sight.norm();
  if (occluders.empty() || !(range > margin))
    return false;
  const double cos_max = std::cos(std::max(2.0 * lidar.azimuth_step_rad, std::atan(margin / range)));
  for (const Eigen::Vector2d& o : occluders) {
    const Eigen::Vector2d to = o - lidar.xy();
    const double r = to.norm();
    if (r > 0.0 && r < range - margin && to.dot(sight) >= cos_max * r * range)
      return true;
  }
  return false;
}

}  // namespace

bool LidarGeometry::occluded(const Eigen::Vector2d& xy, double margin) const {
  const bool out = occluded_by(occluders, *this, xy, margin);
  if (occlusion_log != nullptr)
    occlusion_log->push_back({xy, margin, out});
  return out;
}

bool LidarGeometry::answers_alike(std::span<const Eigen::Vector2d> other_occluders,
                                  std::span<const OcclusionQuery> log) const {
  return std::all_of(log.begin(), log.end(), [&](const OcclusionQuery& q) {
    return occluded_by(other_occluders, *this, q.xy, q.margin) == q.occluded;
  });
}

int LidarGeometry::laser_of(const Eigen::Vector3d& p) const {
  if (elevations_rad.empty())
    return -1;
  const double elevation = std::atan2(p.z() - position.z(), (p.head<2>() - xy()).norm());
  int nearest = 0;
  for (std::size_t i = 1; i < elevations_rad.size(); ++i) {
    if (std::abs(elevations_rad[i] - elevation) <
        std::abs(elevations_rad[static_cast<std::size_t>(nearest)] - elevation))
      nearest = static_cast<int>(i);
  }
  return nearest;
}

LaserLookup::LaserLookup(const std::vector<double>& elevations_rad) {
  std::vector<int> order(elevations_rad.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = static_cast<int>(i);
  // Stable: of equal elevations the first index stays first, and the rank between them maps to it.
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return elevations_rad[static_cast<std::size_t>(a)] < elevations_rad[static_cast<std::size_t>(b)];
  });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const double e = elevations_rad[static_cast<std::size_t>(order[i])];
    if (i > 0) {
      const double below = elevations_rad[static_cast<std::size_t>(order[i - 1])];
      boundaries_.push_back(std::tan(0.5 * (below + e)));
    }
    lasers_.push_back(i > 0 && elevations_rad[static_cast<std::size_t>(order[i - 1])] == e ? lasers_.back()
                                                                                           : order[i]);
  }
}

std::vector<std::size_t> LaserLookup::ranks(std::span<const Eigen::Vector3d> points,
                                            const Eigen::Vector3d& origin) const {
  std::vector<std::size_t> out(points.size(), kNone);
  if (lasers_.empty())
    return out;
  std::size_t hint = 0;  // points arrive firing by firing: the next is mostly a neighbour's laser
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    const double run = (p.head<2>() - origin.head<2>()).norm();
    if (p.allFinite() && run > 0.0) {
      hint = rank((p.z() - origin.z()) / run, hint);
      out[i] = hint;
    }
  }
  return out;
}

}  // namespace rsu::perception
