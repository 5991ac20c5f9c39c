// SPDX-License-Identifier: Apache-2.0
// A vehicle's recorded view (its points and the occluders rsud would pass, dumped from an experiment where
// a fix was hazardously misleading), the LiDAR that saw it, and the check each such test makes: for every
// announced heading error tried, the fix is right (under 0.10 m) or its covariance covers it (NEES within
// the 3-sigma bound), or it is withheld as unbounded.
#pragma once

#include <gtest/gtest.h>

#include <initializer_list>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "eval/consistency.h"
#include "lidar/sensor_model.h"
#include "perception/vehicle_fix.h"

namespace rsu::perception::test {

inline LidarGeometry recorded_lidar(const lidar::SensorModel& model, const Eigen::Vector3d& position,
                                    std::vector<Eigen::Vector2d> occluders = {}) {
  LidarGeometry lidar;
  lidar.position = position;
  for (const double e : model.elevation_deg)
    lidar.elevations_rad.push_back(deg_to_rad(e));
  lidar.azimuth_step_rad = deg_to_rad(model.azimuth_step_deg());
  lidar.occluders = std::move(occluders);
  return lidar;
}

inline void expect_fix_right_or_covered(std::span<const Eigen::Vector3d> points, const VehicleSize& size,
                                        const Eigen::Vector2d& truth, double truth_yaw,
                                        const LidarGeometry& lidar,
                                        std::initializer_list<double> prior_errors_deg) {
  for (const double prior_error_deg : prior_errors_deg) {
    AnnouncedVehicle announced;
    announced.size = size;
    announced.yaw_prior = YawPrior{truth_yaw + deg_to_rad(prior_error_deg), deg_to_rad(10.0)};
    const VehicleFix fix = fix_vehicle(points, announced, lidar);
    if (!fix.ok()) {
      EXPECT_EQ(fix.status(), CorrectionStatus::position_unbounded) << prior_error_deg;
      continue;
    }
    const Eigen::Vector2d error(fix.corrected.pose.x - truth.x(), fix.corrected.pose.y - truth.y());
    const double nees = eval::position_nees(error, fix.corrected.covariance.topLeftCorner<2, 2>());
    EXPECT_TRUE(error.norm() < 0.10 || nees <= eval::kChi2TwoDof3Sigma)
        << "prior " << prior_error_deg << " deg: " << error.norm() << " m off at NEES " << nees << ", yaw "
        << rad_to_deg(angle_distance(fix.corrected.pose.yaw, truth_yaw)) << " deg off";
  }
}

}  // namespace rsu::perception::test
