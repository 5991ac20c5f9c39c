// SPDX-License-Identifier: Apache-2.0
// Time-stamped planar pose measurements fed to the vehicle EKF (map frame ENU, m, rad; docs/design.md §3).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "common/pose.h"
#include "common/time.h"

namespace rsu::fusion {

enum class MeasurementSource : std::uint8_t {
  // The vehicle's own NDT scan-matching pose of its reference point; yaw is a full heading.
  kNdt,
  // An RSU correction: the footprint box centre (not the reference point), and a box yaw that is only
  // known modulo pi (a rectangle looks the same turned by 180 degrees; docs/design.md §1).
  kRsu,
};

struct PoseMeasurement {
  TimeNs time = 0;  // when the pose was true: NDT scan time, or the RSU's sweep time
  MeasurementSource source = MeasurementSource::kNdt;
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // over (x, y, yaw)
};

}  // namespace rsu::fusion
