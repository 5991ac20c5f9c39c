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
  // A car within 10 m of a 128-ring sensor holds thousands (azimuth_thinning.h). Above every car's
  // cluster of a VLP-16 or VLP-32C in the pilot (at most 2,461 points: the SUV 3 m from a VLP-32C 2 m up;
  // their fixes are the same bit for bit); a van's or bus's near a 2 m mount holds more (the pilot
  // matrix's largest: VLP-16 3,233 and 7,109, VLP-32C 7,890 and 14,113) and is thinned.
  std::size_t thin_above_points = 3000;
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

}  // namespace rsu::perception
