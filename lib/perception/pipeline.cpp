#include "perception/pipeline.h"

namespace rsu::perception {

BackgroundModelConfig background_model_config(const PerceptionConfig& config) {
  return {config.background, config.ground_prefilter, config.ground, config.reference_frame,
          config.range_image};
}

PerceptionPipeline::PerceptionPipeline(const PerceptionConfig& config, const Eigen::Vector3d& lidar_position)
    : config_(config),
      lidar_position_(lidar_position),
      background_(background_model_config(config), lidar_position.head<2>()) {}

void PerceptionPipeline::add_background_frame(std::span<const LidarPoint> points) {
  background_.add_background_frame(points);
}

Clustering PerceptionPipeline::cluster(std::span<const LidarPoint> points,
                                       const std::vector<std::uint32_t>& indices) const {
  return config_.clustering_method == ClusteringMethod::grid
             ? cluster_grid(points, indices, config_.clustering)
             : cluster_reference(points, indices, config_.clustering);
}

// The paper's per-frame steps, each one call: foreground, clusters, a rectangle fitted to each.
PerceptionResult PerceptionPipeline::process(std::span<const LidarPoint> points) const {
  const ForegroundSelection foreground = background_.select_foreground(points);
  const Clustering clusters = cluster(points, foreground.indices);
  PerceptionResult result;
  result.objects.reserve(clusters.clusters.size());
  for (const Cluster& c : clusters.clusters) {
    result.objects.push_back({detect(points, c, lidar_xy(), config_.fix.fit), c});
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
  return fix_vehicle(object.points, vehicle, lidar_position_, config_.fix);
}

}  // namespace rsu::perception
