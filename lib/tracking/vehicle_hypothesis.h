// SPDX-License-Identifier: Apache-2.0
// Where the RSU expects an announced vehicle's footprint box at a LiDAR sweep time: its announced pose
// carried forward with its announced motion (CTRV, as the vehicle EKF) and moved from the reference
// point to the box centre (docs/design.md §3), with the covariance grown for the unknowns.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "common/time.h"
#include "v2i/messages.h"

namespace rsu::tracking {

struct VehicleHypothesis {
  std::uint64_t vehicle_id = 0;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // footprint box centre, map frame
  double yaw = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // (centre x, centre y, yaw)
  v2i::BoxSize size;
};

struct HypothesisConfig {
  // Motion uncertainty when the vehicle announced none: town speeds up to about 15 m/s, standing
  // still included, so the along-track spread grows by this much per second of prediction.
  double unknown_speed_sigma_mps = 8.0;
  double unknown_yaw_rate_sigma_rps = 0.3;
  // When announced, the numbers are the vehicle's own estimates: small errors.
  double known_speed_sigma_mps = 0.5;
  double known_yaw_rate_sigma_rps = 0.05;
  // Acceleration noise while predicting (CTRV process noise).
  double accel_sigma_mps2 = 2.0;
  double yaw_accel_sigma_rps2 = 0.5;
};

// The hypothesis for `announcement` at `sweep_time` (earlier or later than its generation time).
VehicleHypothesis predict_hypothesis(const v2i::VehicleAnnouncement& announcement, TimeNs sweep_time,
                                     const HypothesisConfig& config = {});

}  // namespace rsu::tracking
