// SPDX-License-Identifier: Apache-2.0
// The RSU's perception of one whole frame, as the paper runs it (Sec. 3-4): remove the static
// background, cluster what is left, fit a rectangle to each cluster (L-shape fitting). It is a thin
// composition of the parts rsud runs batch by batch (rsu::core::RsuCore::process, docs/architecture.md):
// BackgroundModel, the grid clustering whose components the SweepClusterer grows (a whole frame gives
// the clusters rsud's SweepClusterer releases for it, as for a PCD frame), perception::detect and, per
// matched vehicle, fix_vehicle (vehicle_fix.h). Association with the vehicles that announced their
// size is tracking's job; the caller calls correct() per matched vehicle.
// Used by the per-frame benchmark and the perception tests; rsud itself runs the parts through RsuCore.
//
// Points come in the map frame (the caller applies the LiDAR mount pose) and keep their ring, azimuth and
// firing time, in firing order; the LiDAR's map position is fixed for the pipeline's lifetime.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "lidar/point.h"
#include "perception/background_model.h"
#include "perception/detection.h"
#include "perception/euclidean_clustering.h"
#include "perception/ground_height_filter.h"
#include "perception/range_image_background.h"
#include "perception/reference_frame_background.h"
#include "perception/vehicle_fix.h"

namespace rsu::perception {

struct PerceptionConfig;
// The background part of a perception configuration.
BackgroundModelConfig background_model_config(const PerceptionConfig& config);

struct PerceptionConfig {
  BackgroundMethod background = BackgroundMethod::range_image;
  // Drop near-ground points before the reference-frame or range-image test: far ground returns at
  // grazing incidence move by metres with beam-angle noise (ground_height_filter.h).
  bool ground_prefilter = true;
  GroundHeightFilterConfig ground;
  ReferenceFrameBackgroundConfig reference_frame;
  RangeImageBackgroundConfig range_image;

  // Autoware's tolerance and minimum, but a larger maximum: a car 10 m from a 32- or 128-ring LiDAR
  // returns several thousand points, and Autoware's 1000 would drop it whole.
  ClusteringConfig clustering{
      .tolerance_m = 0.7, .min_points = 10, .max_points = 20000, .distance = ClusterDistance::planar};

  // The rectangle fit (fix.fit, also used for each cluster's fit) and the size correction.
  VehicleFixConfig fix;
};

struct PerceptionStats {
  std::size_t input_points = 0;
  std::size_t foreground_points = 0;
  std::size_t background_points = 0;
  std::size_t invalid_points = 0;
  std::size_t clusters_dropped_small = 0;
  std::size_t clusters_dropped_large = 0;
  std::size_t failed_fits = 0;  // objects whose fit status is not ok (kept, with their status)
};

struct PerceptionResult {
  std::vector<Detection> objects;  // one per released cluster, in order of its first point
  PerceptionStats stats;
};

class PerceptionPipeline {
 public:
  // lidar: the LiDAR in the map frame, its lasers' elevations and azimuth step (lidar_geometry.h).
  PerceptionPipeline(const PerceptionConfig& config, const LidarGeometry& lidar);

  // A frame recorded without vehicles (map frame): becomes part of the reference frame, or trains the
  // range image. Unused by the ground-height method. Until one is added, every non-ground point is
  // foreground.
  void add_background_frame(std::span<const lidar::LidarPoint> points_in_map_frame);

  // Foreground -> clusters -> fit, the frame released whole at its end.
  PerceptionResult process(std::span<const lidar::LidarPoint> points_in_map_frame) const;

  // The fix of one object, for the vehicle matched to it (fix_vehicle with this pipeline's settings).
  VehicleFix correct(const Detection& object, const AnnouncedVehicle& vehicle) const;

  const PerceptionConfig& config() const { return config_; }
  Eigen::Vector2d lidar_xy() const { return lidar_.xy(); }

 private:
  PerceptionConfig config_;
  LidarGeometry lidar_;
  BackgroundModel background_;
};

}  // namespace rsu::perception
