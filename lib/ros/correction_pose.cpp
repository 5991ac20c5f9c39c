// SPDX-License-Identifier: Apache-2.0
#include "ros/correction_pose.h"

#include <cmath>

namespace rsu::ros {

RosPoseWithCovariance to_ros_pose(const v2i::Correction& c) {
  RosPoseWithCovariance p;
  p.position = {c.pose.x, c.pose.y, 0.0};
  p.orientation = {0.0, 0.0, std::sin(c.pose.yaw / 2), std::cos(c.pose.yaw / 2)};
  // (x, y, yaw) of the 3x3 are rows/columns (0, 1, 5) of the 6x6.
  constexpr std::array<int, 3> kIndex = {0, 1, 5};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      p.covariance[static_cast<std::size_t>(kIndex[i] * 6 + kIndex[j])] = c.pose_covariance(i, j);
  }
  for (const int k : {2, 3, 4})
    p.covariance[static_cast<std::size_t>(k * 6 + k)] = kUnknownVariance;
  return p;
}

}  // namespace rsu::ros
