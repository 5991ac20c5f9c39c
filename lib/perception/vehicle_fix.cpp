#include "perception/vehicle_fix.h"

#include <vector>

#include "common/angles.h"

namespace rsu::perception {

VehicleFix fix_vehicle(std::span<const Eigen::Vector3d> points, const AnnouncedVehicle& vehicle,
                       const Eigen::Vector3d& lidar_position, const VehicleFixConfig& config) {
  VehicleFix out;
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite()) {
      xy.emplace_back(p.x(), p.y());
    }
  }
  out.points_used = xy.size();
  const Eigen::Vector2d lidar_xy = lidar_position.head<2>();
  out.fit = fit_rectangle(xy, lidar_xy, config.fit);

  // The correction judges faces with the fit's own support rules, and the fix's yaw is quantised by
  // the orientation search that produced the fit.
  CorrectionConfig correction = config.correction;
  correction.fit = config.fit;
  correction.covariance.search_resolution_rad =
      deg_to_rad(config.fit.search.method == OrientationSearchMethod::exhaustive
                     ? config.fit.search.exhaustive_step_deg
                     : config.fit.search.fine_resolution_deg);
  if (config.method == CorrectionMethod::algorithm1) {
    out.corrected = correct_algorithm1(out.fit, vehicle.size, lidar_xy, correction.covariance);
  } else {
    out.corrected = correct_improved(out.fit, xy, vehicle.size, lidar_xy, vehicle.yaw_prior, correction);
  }
  return out;
}

}  // namespace rsu::perception
