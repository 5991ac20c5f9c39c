// SPDX-License-Identifier: Apache-2.0
// One detected object: a cluster of foreground points and the rectangle fitted to it (L-shape fitting,
// paper Sec. 3.1), before anything knows which vehicle it is. The one type every step after clustering
// shares: the per-frame pipeline returns it, the RSU's sweep gathers it, association gates its
// rectangle against the announced vehicles (tracking).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/time.h"
#include "lidar/point.h"
#include "perception/azimuth_thinning.h"
#include "perception/l_shape_fitting.h"
#include "perception/lidar_geometry.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

struct Detection {
  std::vector<Eigen::Vector3d> points;  // map frame
  TimeNs sweep_time_ns = 0;             // mean firing time of its points: when the LiDAR swept it
  RectangleFit fit;                     // its status says whether a rectangle could be fitted
  bool ahead_of_open = false;           // SweptCluster::ahead_of_open: may continue behind a nearer one
  std::vector<Eigen::AlignedBox2d> open_beyond;  // SweptCluster::open_beyond
  // Its points as detect thinned them for the rectangle (FitThinning given; none without): as fix_vehicle
  // thins them with the same LiDAR and threshold, so the fix of a vehicle of this detection alone takes
  // it (a dense cluster's thinning was a quarter to a third of its fix: issue 16).
  std::optional<AzimuthThinning> thinning;
};

// Which of a dense cluster's points the rectangle is fitted to: every k-th azimuth column of each laser's
// trace when it has more than `above_points` (azimuth_thinning.h; `lidar` tells its lasers apart), as
// fix_vehicle fits and fixes it (VehicleFixConfig::thin_above_points). The detection keeps all its points.
// Default: all.
struct FitThinning {
  const LidarGeometry* lidar = nullptr;
  std::size_t above_points = 0;
};

// The detection made of `points` (map frame, at least one): their mean firing time and the rectangle
// fitted to their footprint as seen from the LiDAR at `lidar_xy`.
Detection detect(std::span<const lidar::LidarPoint> points, const Eigen::Vector2d& lidar_xy,
                 const LShapeFitConfig& config, const FitThinning& thinning = {});
// The same for the points `indices` of `frame`.
Detection detect(std::span<const lidar::LidarPoint> frame, std::span<const std::uint32_t> indices,
                 const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& config);

}  // namespace rsu::perception
