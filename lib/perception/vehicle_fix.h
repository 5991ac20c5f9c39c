// SPDX-License-Identifier: Apache-2.0
// One connected vehicle's fix from the LiDAR points on it: the paper's per-vehicle steps (Sec. 3: L-shape
// fitting, then size correction with the size the vehicle announced, Algorithm 1 or the improved
// correction), with the fix's covariance or the reason why there is no fix.
//
// This is the one function every part that turns points into a fix calls: rsud's core (lib/core), the
// pilot experiment (eval/pilot), the accuracy tests. They pass the same configuration: VehicleFixConfig's
// defaults are what rsud runs unless its configuration file says otherwise (deploy/rsud.yaml,
// perception.correction); an experiment that measures another setting says so in its output.
//
// Input: the vehicle's points in the map frame (x, y, z), what the vehicle announced (its box size, its
// heading predicted to the sweep time), the LiDAR (its position, its lasers' elevations, the road's
// height: lidar_geometry.h). Points that are not finite are ignored. The improved correction fits the
// rectangle to the lower body's points where there are enough (size_correction.h), Algorithm 1 to all.
#pragma once

#include <cstddef>
#include <optional>
#include <span>

#include <Eigen/Core>

#include "perception/azimuth_thinning.h"
#include "perception/l_shape_fitting.h"
#include "perception/lidar_geometry.h"
#include "perception/rectangle_fit.h"
#include "perception/size_correction.h"

namespace rsu::perception {

enum class CorrectionMethod { algorithm1, improved };

struct VehicleFixConfig {
  LShapeFitConfig fit;
  CorrectionMethod method = CorrectionMethod::improved;
  CorrectionConfig correction;  // the improved correction's rules (size_correction.h)
  // A cluster with more finite points than this is fixed from every k-th azimuth column of each laser's
  // trace, its ends kept (azimuth_thinning.h), k chosen so that about this many remain; 0: never thinned.
  // A car within 10 m of a 128-ring sensor holds thousands (azimuth_thinning.h), and so does a van or bus
  // near a VLP 2 m up (the pilot matrix's largest: VLP-16 3,233 and 7,109, VLP-32C 7,890 and 14,113); a
  // VLP-32C's car within ~8 m holds 1,500-2,461. 800 (issue 16): a near dense car's fit and fix, prepared
  // ahead of its release, holds rsud's loop and the release packets behind it (3,000 -> 1,500: up to
  // 3-4.5 ms of CPU before; 1,500 -> 800 on 2026-12-01: the OS1-128 load test's p99 6.07, 5.96 ->
  // 5.52, 5.69 ms, the VLP-32C's 4.88, 5.01 -> 4.47, 4.51 ms); the pilot matrix's cells over 6-36 m
  // moved by -0.2 to +1.6 points (3,000 -> 1,500) and -0.7 to +1.0 (1,500 -> 800), HMI 0 and none
  // beyond 3 sigma in every cell either way (README, Benchmarks).
  std::size_t thin_above_points = 800;
};

// What the vehicle told the RSU, carried to the time the LiDAR swept it.
struct AnnouncedVehicle {
  VehicleSize size;
  std::optional<YawPrior> yaw_prior;  // its own heading estimate at the sweep time, if it has one
};

struct VehicleFix {
  CorrectedPose corrected;      // status (ok or why not), pose, covariance, how the yaw was resolved
  RectangleFit fit;             // the L-shape fit the correction started from (its status says if it failed)
  std::size_t points_used = 0;  // the finite points fixed from (after thinning)
  int azimuth_stride = 1;       // every k-th azimuth column of each laser's trace was used (1: all)

  bool ok() const { return corrected.ok(); }
  CorrectionStatus status() const { return corrected.status; }
};

VehicleFix fix_vehicle(std::span<const Eigen::Vector3d> points, const AnnouncedVehicle& vehicle,
                       const LidarGeometry& lidar, const VehicleFixConfig& config = {});
// The same from `points` already thinned: `thinning` is thin_along_azimuth(points, lidar,
// config.thin_above_points) (a detection's, detection.h), so that a dense cluster is not thinned twice.
VehicleFix fix_vehicle(std::span<const Eigen::Vector3d> points, const AzimuthThinning& thinning,
                       const AnnouncedVehicle& vehicle, const LidarGeometry& lidar,
                       const VehicleFixConfig& config = {});

}  // namespace rsu::perception
