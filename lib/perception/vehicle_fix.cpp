// SPDX-License-Identifier: Apache-2.0
#include "perception/vehicle_fix.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "common/angles.h"
#include "perception/azimuth_thinning.h"

namespace rsu::perception {
namespace {

// The xy of the points the rectangle is fitted to: the lower body's when it has enough points for a
// fit (its outline is the footprint), else all of them. The lower body is not all of the footprint on
// a van: its bonnet's top (1.2 of 2.45 m) lies within it, and a laser's trace across it, with the
// glasshouse's far corner, made a diagonal "face" 20 deg off (`rsu-pilot matrix`, a VLP-32C 6 m up): so
// it is fitted only where enough points lie below the bonnet (end_body_height) too.
std::vector<Eigen::Vector2d> outline_points(std::span<const Eigen::Vector3d> points, const VehicleSize& size,
                                            const LidarGeometry& lidar, const VehicleFixConfig& config,
                                            bool lower_body_only) {
  const double lower = lower_body_height(size, config.correction);
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite() && (!lower_body_only || p.z() - lidar.ground_z <= lower))
      xy.emplace_back(p.x(), p.y());
  }
  return xy;
}

}  // namespace

VehicleFix fix_vehicle(std::span<const Eigen::Vector3d> cluster, const AnnouncedVehicle& vehicle,
                       const LidarGeometry& lidar, const VehicleFixConfig& config) {
  VehicleFix out;
  // A dense cluster is fixed from fewer of its points (azimuth_thinning.h); a sparse one as it is.
  const AzimuthThinning thinned = thin_along_azimuth(cluster, lidar, config.thin_above_points);
  const std::span<const Eigen::Vector3d> points =
      thinned.stride > 1 ? std::span<const Eigen::Vector3d>(thinned.points) : cluster;
  out.azimuth_stride = thinned.stride;
  const std::vector<Eigen::Vector2d> all = outline_points(points, vehicle.size, lidar, config, false);
  out.points_used = all.size();

  // The correction judges faces with the fit's own support rules, and the fix's yaw is quantised by
  // the orientation search that produced the fit. Its points lie k azimuth steps apart along a trace
  // when thinned.
  CorrectionConfig correction = config.correction;
  correction.fit = config.fit;
  correction.covariance.azimuth_resolution_rad = lidar.azimuth_step_rad * static_cast<double>(thinned.stride);
  correction.covariance.search_resolution_rad =
      deg_to_rad(config.fit.search.method == OrientationSearchMethod::exhaustive
                     ? config.fit.search.exhaustive_step_deg
                     : config.fit.search.fine_resolution_deg);
  if (config.method == CorrectionMethod::algorithm1) {
    out.fit = fit_rectangle(all, lidar.xy(), config.fit);
    out.corrected = correct_algorithm1(out.fit, vehicle.size, lidar.xy(), correction.covariance);
    return out;
  }
  std::vector<Eigen::Vector2d> outline = outline_points(points, vehicle.size, lidar, config, true);
  const double below_bonnet = end_body_height(vehicle.size, config.correction);
  const auto under_bonnet = std::count_if(points.begin(), points.end(), [&](const Eigen::Vector3d& p) {
    return p.allFinite() && p.z() - lidar.ground_z <= below_bonnet;
  });
  const auto enough = static_cast<std::ptrdiff_t>(config.correction.min_lower_body_points);
  if (static_cast<std::ptrdiff_t>(outline.size()) >= enough && under_bonnet >= enough) {
    out.fit = fit_rectangle(outline, lidar.xy(), config.fit);
  }
  if (!out.fit.ok()) {
    outline = all;
    out.fit = fit_rectangle(outline, lidar.xy(), config.fit);
  }
  out.corrected =
      correct_improved(out.fit, outline, points, vehicle.size, lidar, vehicle.yaw_prior, correction);
  return out;
}

}  // namespace rsu::perception
