// SPDX-License-Identifier: Apache-2.0
// The vehicle's own LiDAR self-localization for the realistic experiment (paper Sec. 4): NDT scan
// matching (pcl::NormalDistributionsTransform) against a point-cloud map, with only scan matching (no GNSS,
// no IMU, as in the paper), the initial guess from the previous pose plus constant-velocity motion.
// Parameters are Autoware's ndt_scan_matcher and its input preprocessing defaults (docs/design.md §2); the
// scenario file states every one of them.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "common/pose.h"
#include "lidar/point.h"

namespace rsu::eval {

struct NdtConfig {
  // ndt_scan_matcher (Autoware): voxel resolution, Newton step size, transformation epsilon, iterations.
  double resolution_m = 2.0;
  double step_size_m = 0.1;
  double transformation_epsilon = 0.01;  // m: Autoware's trans_epsilon, a step length (see the .cpp)
  int max_iterations = 30;
  // Input preprocessing (Autoware's localization pointcloud preprocessor): crop to a measurement range,
  // 3 m voxel grid, then a random subset of 1500 points.
  double crop_range_m = 60.0;
  double voxel_leaf_m = 3.0;
  int random_sample_points = 1500;
  // The pose covariance NDT reports. Fixed: Autoware's default (output_pose_covariance), 0.15 m and
  // 0.025 rad standard deviations, whatever the match. Laplace: the match's own statement, after
  // Autoware's LAPLACE_APPROXIMATION: `laplace_scale` times the inverse of the score's curvature at the
  // solution (PCL's score is no calibrated log-likelihood: the scale is measured), at least
  // `laplace_min_sigma_*`, plus what a poor fit adds: scan points far from the map (unmapped objects:
  // other vehicles, a mast) pull the match off without flattening its curvature, and in the corridor the
  // error grew with the fitness above its nominal value (RMS 0.01 m at 0.045 m^2, 0.07 m at 0.085 m^2,
  // 0.13 m at 0.15 m^2: README), so each m^2 of fitness above `fitness_nominal_m2` adds
  // `fitness_sigma_m_per_m2` (and `fitness_sigma_rad_per_m2` in yaw) to the standard deviation.
  // The curvature cannot see a match that slides along a street with nothing along it (the degraded
  // corridor's NDT was 0.46 m off claiming 6 cm): the degeneracy indicator says so (NdtResult), and the
  // vehicle weakens such poses itself (vehicle/vehicle_core.h).
  enum class CovarianceEstimate { kFixed, kLaplace };
  CovarianceEstimate covariance_estimate = CovarianceEstimate::kFixed;
  double output_sigma_xy_m = 0.15;
  double output_sigma_yaw_rad = 0.025;
  double laplace_scale = 4.0;
  double laplace_min_sigma_xy_m = 0.02;
  double laplace_min_sigma_yaw_rad = 0.005;
  double fitness_nominal_m2 = 0.045;
  double fitness_sigma_m_per_m2 = 1.5;
  double fitness_sigma_rad_per_m2 = 0.1;
  // Points within this radius of the sensor are the vehicle itself.
  double self_filter_radius_m = 3.0;
};

// The match and how it went: the quality indicator the vehicle passes on with each pose
// (vehicle/ndt_quality.h), so that it knows when its own localization is the one that failed.
struct NdtResult {
  Pose2 pose;                                            // the vehicle's footprint centre and yaw, map frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // (x, y, yaw), as NdtConfig::covariance_estimate
  // Autoware's fixed covariance (NdtConfig::output_sigma_*), whichever is reported: the initial guess's
  // predictor is tuned with it (vehicle_ndt_run.cpp).
  Eigen::Matrix3d fixed_covariance = Eigen::Matrix3d::Zero();
  // Stopped because a step fell below the transformation epsilon, not at the iteration cap (PCL's own
  // hasConverged() is true at the cap as well).
  bool converged = false;
  int iterations = 0;
  double fitness = 0.0;  // PCL's fitness score: mean squared distance of the aligned scan to the map, m^2
  // sqrt(largest / smallest eigenvalue) of the score's curvature in x, y at the solution: how much more
  // weakly the match holds the vehicle in its weakest horizontal direction than in its strongest (a
  // street with nothing along it: large). The fitness cannot see that: sliding along a uniform facade
  // fits it as well.
  double degeneracy = 1.0;
  // The direction of that weakest hold (map frame, rad, modulo pi): where the match may slide (along the
  // street). The vehicle weakens a degenerate pose along it only (vehicle/ndt_quality.h).
  double weak_axis_rad = 0.0;
  std::size_t scan_points = 0;
};

class NdtLocalizer {
 public:
  NdtLocalizer(const NdtConfig& config, const std::vector<Eigen::Vector3f>& map_points, std::uint64_t seed);
  ~NdtLocalizer();
  NdtLocalizer(const NdtLocalizer&) = delete;
  NdtLocalizer& operator=(const NdtLocalizer&) = delete;

  // scan: points in the sensor frame; sensor_in_vehicle: the LiDAR's mount on the vehicle (vehicle frame:
  // footprint centre on the ground, x forward); guess: the initial vehicle pose.
  NdtResult align(const std::vector<lidar::LidarPoint>& scan, const Pose3& sensor_in_vehicle,
                  const Pose2& guess);

 private:
  struct Impl;
  NdtConfig config_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsu::eval
