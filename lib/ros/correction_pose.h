// SPDX-License-Identifier: Apache-2.0
// A correction (lib/v2i Correction: footprint centre x, y, yaw with a 3x3 covariance over (x, y, yaw))
// as geometry_msgs/PoseWithCovariance, pure. The 6x6 covariance is row-major over (x, y, z, rotation
// about X, about Y, about Z), as ROS defines it. The RSU measures neither z, roll nor pitch: they are
// reported as 0 with kUnknownVariance on the diagonal and no correlation, the convention ROS
// consumers (robot_localization, Autoware's EKF localizer) read as "do not use". Yaw is about +z,
// counter-clockwise from east (docs/design.md §3), so the quaternion is a pure rotation about z.
#pragma once

#include <array>

#include "v2i/messages.h"

namespace rsu::ros {

// Variance (m^2 for z, rad^2 for roll and pitch) that says "unknown".
inline constexpr double kUnknownVariance = 1e6;

struct RosPoseWithCovariance {
  std::array<double, 3> position{};               // x, y, z (m)
  std::array<double, 4> orientation{0, 0, 0, 1};  // quaternion x, y, z, w
  std::array<double, 36> covariance{};            // row-major 6x6
};

RosPoseWithCovariance to_ros_pose(const v2i::Correction& correction);

}  // namespace rsu::ros
