// SPDX-License-Identifier: Apache-2.0
#include "perception/pipeline.h"

namespace rsu::perception {

BackgroundModelConfig background_model_config(const PerceptionConfig& config) {
  return {config.background, config.ground_prefilter, config.ground, config.reference_frame,
          config.range_image};
}

PerceptionPipeline::PerceptionPipeline(const PerceptionConfig& config, const LidarGeometry& lidar)
    : config_(config), lidar_(lidar), background_(background_model_config(config), lidar.xy()) {}

void PerceptionPipeline::add_background_frame(std::span<const lidar::LidarPoint> points) {
  background_.add_background_frame(points);
}

// The paper's per-frame steps with rsud's parts, each one call: foreground, clusters, a rectangle
// fitted to each. A whole frame clusters with cluster_grid directly: the SweepClusterer grows the same
// components point by point (incremental_clustering.h), and released whole it releases exactly these
// clusters (test_pipeline checks it), with per-point sweep bookkeeping a whole frame does not need.
PerceptionResult PerceptionPipeline::process(std::span<const lidar::LidarPoint> points) const {
  const ForegroundSelection foreground = background_.select_foreground(points);
  const Clustering clusters = cluster_grid(points, foreground.indices, config_.clustering);
  PerceptionResult result;
  result.objects.reserve(clusters.clusters.size());
  for (const Cluster& c : clusters.clusters) {
    result.objects.push_back(detect(points, c, lidar_xy(), config_.fix.fit));
    result.stats.failed_fits += result.objects.back().fit.ok() ? 0 : 1;
  }
  PerceptionStats& s = result.stats;
  s.input_points = points.size();
  s.foreground_points = foreground.indices.size();
  s.background_points = foreground.background;
  s.invalid_points = foreground.invalid + clusters.invalid_points;
  s.clusters_dropped_small = clusters.dropped_small;
  s.clusters_dropped_large = clusters.dropped_large;
  return result;
}

VehicleFix PerceptionPipeline::correct(const Detection& object, const AnnouncedVehicle& vehicle) const {
  return fix_vehicle(object.points, vehicle, lidar_, config_.fix);
}

}  // namespace rsu::perception
