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

PerceptionResult PerceptionPipeline::process(std::span<const LidarPoint> points) const {
  PerceptionResult result;
  const ForegroundSelection fg = background_.select_foreground(points);
  result.stats.input_points = points.size();
  result.stats.foreground_points = fg.indices.size();
  result.stats.background_points = fg.background;
  result.stats.invalid_points = fg.invalid;

  const Clustering clusters = config_.clustering_method == ClusteringMethod::grid
                                  ? cluster_grid(points, fg.indices, config_.clustering)
                                  : cluster_reference(points, fg.indices, config_.clustering);
  result.stats.clusters_dropped_small = clusters.dropped_small;
  result.stats.clusters_dropped_large = clusters.dropped_large;
  result.stats.invalid_points += clusters.invalid_points;

  result.objects.reserve(clusters.clusters.size());
  for (const Cluster& cluster : clusters.clusters) {
    DetectedObject object;
    object.point_indices = cluster;
    object.points.reserve(cluster.size());
    std::vector<Eigen::Vector2d> footprint;
    footprint.reserve(cluster.size());
    const TimeNs t0 = points[cluster.front()].time_ns;
    TimeNs offset_sum = 0;  // relative to t0: a frame spans 0.1 s, so the sum cannot overflow
    for (const std::uint32_t i : cluster) {
      const LidarPoint& p = points[i];
      object.points.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y),
                                 static_cast<double>(p.z));
      footprint.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y));
      offset_sum += p.time_ns - t0;
    }
    object.sweep_time_ns = t0 + offset_sum / static_cast<TimeNs>(cluster.size());
    object.fit = fit_rectangle(footprint, lidar_xy(), config_.fix.fit);
    if (!object.fit.ok()) {
      ++result.stats.failed_fits;
    }
    result.objects.push_back(std::move(object));
  }
  return result;
}

VehicleFix PerceptionPipeline::correct(const DetectedObject& object, const AnnouncedVehicle& vehicle) const {
  return fix_vehicle(object.points, vehicle, lidar_position_, config_.fix);
}

}  // namespace rsu::perception
