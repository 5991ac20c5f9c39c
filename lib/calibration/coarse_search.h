// SPDX-License-Identifier: Apache-2.0
// The coarse stage of the mount calibration: from a rough initial pose (a hand-held GNSS and a compass:
// metres and 10-20 deg off) to within a fraction of a metre and a degree, by a grid search over x, y and
// yaw scoring how many background points land in voxels the map occupies. Height, roll and pitch stay
// as given (a pole is near vertical and its height is measured); the fine stage frees them.
#pragma once

#include <cstdint>
#include <optional>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "common/pose.h"

namespace rsu::calibration {

// The voxel of side resolution_m holding p, as one key (21 bits per axis); none unless p is finite and
// within +-1M voxels of the origin on each axis.
std::optional<std::int64_t> voxel_key(const Eigen::Vector3d& p, double resolution_m);

// Which voxels of side `resolution_m` hold at least one map point (points without a key, e.g. the NaN
// of an organized cloud, are left out; such a query is never occupied).
class VoxelOccupancy {
 public:
  VoxelOccupancy(const std::vector<Eigen::Vector3f>& map_points, double resolution_m);
  bool occupied(const Eigen::Vector3d& p) const;
  double resolution_m() const { return resolution_m_; }

 private:
  double resolution_m_;
  std::unordered_set<std::int64_t> voxels_;
};

// A box of candidate poses around a centre: x, y within +-half_extent_m in steps of step_m, yaw within
// +-half_yaw_rad in steps of yaw_step_rad (the yaw turns the scan about the sensor).
struct SearchGrid {
  double half_extent_m = 3.0;
  double step_m = 0.5;
  double half_yaw_rad = 0.35;
  double yaw_step_rad = 0.0175;
};

struct CoarseMatch {
  Pose3 pose;
  std::size_t hits = 0;  // background points in occupied voxels at `pose`
  std::size_t points = 0;
};

// Points in the sensor frame. The best candidate (most hits; ties keep the one nearest the centre).
CoarseMatch search_pose(const std::vector<Eigen::Vector3d>& sensor_points, const VoxelOccupancy& map,
                        const Pose3& centre, const SearchGrid& grid);

}  // namespace rsu::calibration
