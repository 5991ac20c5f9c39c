// SPDX-License-Identifier: Apache-2.0
// Poses in the map frame (ENU, metres, radians; docs/design.md §3).
#pragma once

#include <Eigen/Geometry>

namespace rsu {

// A planar pose: position of the footprint centre and yaw counter-clockwise from +x.
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

// A rigid 3D pose. Rotation is R = Rz(yaw) * Ry(pitch) * Rx(roll) (intrinsic z-y'-x'', as ROS).
struct Pose3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  double roll = 0.0;
  double pitch = 0.0;
  double yaw = 0.0;

  Eigen::Isometry3d to_isometry() const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    t.translation() = Eigen::Vector3d(x, y, z);
    return t;
  }

  bool operator==(const Pose3&) const = default;
};

}  // namespace rsu
