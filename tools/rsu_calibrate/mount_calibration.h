// SPDX-License-Identifier: Apache-2.0
// rsu-calibrate's registration: the RSU's background scan (sensor frame) against the street's map, from
// a rough initial mount, coarse to fine: a grid search over x, y, yaw on a 1 m then a 0.3 m voxel
// occupancy of the map (lib/calibration/coarse_search.h), then point-to-plane Gauss-Newton against the
// map's local planes with a shrinking match distance (lib/calibration/point_to_plane.h), all six
// parameters free. The covariance is the inverse of the fit's information at the solution, scaled by
// the residuals; the verdict says whether to trust it (lib/calibration/mount_verdict.h).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "calibration/coarse_search.h"
#include "calibration/mount_verdict.h"
#include "common/angles.h"
#include "common/pose.h"

namespace rsu::tools {

struct CalibrationConfig {
  calibration::SearchGrid coarse{3.0, 0.5, deg_to_rad(20.0), deg_to_rad(1.0)};
  double coarse_voxel_m = 1.0;
  calibration::SearchGrid medium{0.5, 0.1, deg_to_rad(1.0), deg_to_rad(0.2)};
  double medium_voxel_m = 0.3;
  std::size_t search_points = 3000;   // background points the grid search scores
  double background_spacing_m = 0.2;  // one background point per cell of this size for the fine stage
  double min_range_m = 1.0;           // closer returns are the pole and the cabinet
  int plane_neighbours = 8;           // map points a local plane is fitted to
  double max_plane_thickness = 0.05;  // smallest / middle eigenvalue of those points' scatter
  std::vector<double> match_distances_m{1.0, 0.5, 0.25, 0.15};
  int iterations_per_distance = 10;
  double huber_sigmas = 3.0;
  // The sensor's noise (its data sheet; the simulator's defaults), for each point's expected residual:
  // range noise along the beam, angular noise across it, projected on the plane's normal.
  double range_sigma_m = 0.02;
  double angle_sigma_rad = 0.001;
  // Beams meeting a surface more obliquely than this (deg from its normal) are left out: there the
  // angular noise turns into a range error that is not zero-mean (the far ground).
  double max_incidence_deg = 70.0;
  calibration::VerdictLimits limits;
  calibration::ModelFloor floor;
};

struct CalibrationResult {
  Pose3 initial;
  Pose3 coarse;  // after the grid searches
  Pose3 pose;    // the mount
  calibration::MountUncertainty uncertainty;
  calibration::PlaneFit fit;  // at `pose`
  calibration::VerdictResult verdict;
  calibration::CoarseMatch search;
  int iterations = 0;
  std::size_t background_points = 0;  // used by the fine stage
  std::size_t map_points = 0;         // within the background's reach of the initial pose
};

CalibrationResult calibrate_mount(const std::vector<Eigen::Vector3d>& background_sensor,
                                  const std::vector<Eigen::Vector3f>& map, const Pose3& initial,
                                  const CalibrationConfig& config = {});

}  // namespace rsu::tools
