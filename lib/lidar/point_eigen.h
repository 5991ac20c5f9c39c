// SPDX-License-Identifier: Apache-2.0
// A LidarPoint's position as the geometry takes it: Eigen, double. The points stay floats (point.h,
// free of Eigen: every source fills them); the computations on them are double.
#pragma once

#include <Eigen/Core>

#include "lidar/point.h"

namespace rsu::lidar {

inline Eigen::Vector3d position_of(const LidarPoint& p) {
  return Eigen::Vector3f(p.x, p.y, p.z).cast<double>();
}

}  // namespace rsu::lidar
