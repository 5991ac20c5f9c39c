#include "perception/pipeline.h"

#include "common/angles.h"

namespace rsu::perception {

BackgroundModelConfig background_model_config(const PerceptionConfig& config) {
  return {config.background, config.ground_prefilter, config.ground, config.reference_frame,
          config.range_image};
}

PerceptionPipeline::PerceptionPipeline(const PerceptionConfig& config, const Eigen::Vector2d& lidar_xy)
    : config_(config), lidar_xy_(lidar_xy), background_(background_model_config(config), lidar_xy) {}

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
    object.footprint.reserve(cluster.size());
    const TimeNs t0 = points[cluster.front()].time_ns;
    TimeNs offset_sum = 0;  // relative to t0: a frame spans 0.1 s, so the sum cannot overflow
    for (const std::uint32_t i : cluster) {
      object.footprint.emplace_back(static_cast<double>(points[i].x), static_cast<double>(points[i].y));
      offset_sum += points[i].time_ns - t0;
    }
    object.sweep_time_ns = t0 + offset_sum / static_cast<TimeNs>(cluster.size());
    object.fit = fit_rectangle(object.footprint, lidar_xy_, config_.fit);
    if (!object.fit.ok()) {
      ++result.stats.failed_fits;
    }
    result.objects.push_back(std::move(object));
  }
  return result;
}

CorrectedPose PerceptionPipeline::correct(const DetectedObject& object, const VehicleSize& size,
                                          const std::optional<YawPrior>& prior) const {
  return perception::correct(object.fit, object.footprint, size, lidar_xy_, prior, config_);
}

CorrectedPose correct(const RectangleFit& fit, std::span<const Eigen::Vector2d> cluster_xy,
                      const VehicleSize& size, const Eigen::Vector2d& lidar_xy,
                      const std::optional<YawPrior>& prior, const PerceptionConfig& config) {
  // The fix's yaw is quantised by the orientation search that produced the fit.
  CorrectionConfig correction = config.correction;
  correction.fit = config.fit;
  correction.covariance.search_resolution_rad =
      deg_to_rad(config.fit.search.method == OrientationSearchMethod::exhaustive
                     ? config.fit.search.exhaustive_step_deg
                     : config.fit.search.fine_resolution_deg);
  if (config.correction_method == CorrectionMethod::algorithm1) {
    return correct_algorithm1(fit, size, lidar_xy, correction.covariance);
  }
  return correct_improved(fit, cluster_xy, size, lidar_xy, prior, correction);
}

}  // namespace rsu::perception
