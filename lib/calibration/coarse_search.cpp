// SPDX-License-Identifier: Apache-2.0
#include "calibration/coarse_search.h"

#include <cmath>

namespace rsu::calibration {

namespace {
constexpr std::int64_t kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::int64_t kAxisMask = (std::int64_t{1} << kAxisBits) - 1;
}  // namespace

VoxelOccupancy::VoxelOccupancy(const std::vector<Eigen::Vector3f>& map_points, double resolution_m)
    : resolution_m_(resolution_m) {
  voxels_.reserve(map_points.size());
  for (const Eigen::Vector3f& p : map_points)
    if (const std::optional<std::int64_t> key = voxel_key(p.cast<double>(), resolution_m_))
      voxels_.insert(*key);
}

std::optional<std::int64_t> voxel_key(const Eigen::Vector3d& p, double resolution_m) {
  // The mount check asks for every point of every rotation, at each voxel size (issue 16): one division
  // per axis (a test for a key, then the key, took two), and floor by truncation, exact within the limit.
  constexpr double kLimit = static_cast<double>(kAxisOffset - 1);
  std::int64_t k = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double cell = p[axis] / resolution_m;
    if (!(std::abs(cell) < kLimit))  // also false for NaN
      return std::nullopt;
    auto below = static_cast<std::int64_t>(cell);  // towards 0
    below -= static_cast<double>(below) > cell ? 1 : 0;
    k = (k << kAxisBits) | ((below + kAxisOffset) & kAxisMask);
  }
  return k;
}

bool VoxelOccupancy::occupied(const Eigen::Vector3d& p) const {
  // A point without a key (NaN, beyond the key's range) is never occupied: converting its cell to an
  // integer is undefined (clang's UBSan reports it as float-cast-overflow; GCC's leaves that check out).
  const std::optional<std::int64_t> key = voxel_key(p, resolution_m_);
  return key && voxels_.contains(*key);
}

CoarseMatch search_pose(const std::vector<Eigen::Vector3d>& sensor_points, const VoxelOccupancy& map,
                        const Pose3& centre, const SearchGrid& grid) {
  CoarseMatch best;
  best.pose = centre;
  best.points = sensor_points.size();
  double best_offset = 0.0;
  bool first = true;
  const int xy_steps = static_cast<int>(std::floor(grid.half_extent_m / grid.step_m + 1e-9));
  const int yaw_steps = static_cast<int>(std::floor(grid.half_yaw_rad / grid.yaw_step_rad + 1e-9));
  std::vector<Eigen::Vector3d> rotated(sensor_points.size());
  for (int k = -yaw_steps; k <= yaw_steps; ++k) {
    Pose3 candidate = centre;
    candidate.yaw = centre.yaw + k * grid.yaw_step_rad;
    const Eigen::Matrix3d rotation = candidate.to_isometry().linear();
    for (std::size_t i = 0; i < sensor_points.size(); ++i)
      rotated[i] = rotation * sensor_points[i];
    for (int ix = -xy_steps; ix <= xy_steps; ++ix) {
      for (int iy = -xy_steps; iy <= xy_steps; ++iy) {
        const Eigen::Vector3d shift(centre.x + ix * grid.step_m, centre.y + iy * grid.step_m, centre.z);
        std::size_t hits = 0;
        for (const Eigen::Vector3d& p : rotated)
          hits += map.occupied(p + shift) ? 1 : 0;
        // Distance from the centre in grid steps, so that a tie keeps the candidate nearest the guess.
        const double offset = std::hypot(ix, iy) + std::abs(k);
        if (first || hits > best.hits || (hits == best.hits && offset < best_offset)) {
          first = false;
          best.hits = hits;
          best_offset = offset;
          best.pose = candidate;
          best.pose.x = shift.x();
          best.pose.y = shift.y();
        }
      }
    }
  }
  return best;
}

}  // namespace rsu::calibration
