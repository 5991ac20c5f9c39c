#include "perception/pipeline.h"

namespace rsu::perception {
namespace {

// A whole frame is released whole, so the release rule's sensor geometry plays no part: the clusterer
// only needs a rotation rate for its gap rule (a gap of two rotations restarts the stream), and at
// 1 Hz no gap within one frame reaches it.
constexpr double kWholeFrameRotationHz = 1.0;

}  // namespace

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

// The paper's per-frame steps with rsud's parts, each one call: foreground, clusters, a rectangle
// fitted to each.
PerceptionResult PerceptionPipeline::process(std::span<const LidarPoint> points) const {
  SweepClusterer clusterer(SweepConfig{}, config_.clustering, lidar_xy(), kWholeFrameRotationHz, 0.0);
  std::size_t background = 0;
  for (const LidarPoint& p : points) {
    const PointClass c = background_.classify(p);
    background += c == PointClass::background ? 1 : 0;
    clusterer.add(p, c == PointClass::foreground);
  }
  const std::vector<SweptCluster> clusters = clusterer.release_all();
  PerceptionResult result;
  result.objects.reserve(clusters.size());
  for (const SweptCluster& c : clusters) {
    result.objects.push_back(detect(c.points, lidar_xy(), config_.fix.fit));
    result.stats.failed_fits += result.objects.back().fit.ok() ? 0 : 1;
  }
  const SweepClustererStats& cs = clusterer.stats();
  PerceptionStats& s = result.stats;
  s.input_points = points.size();
  s.foreground_points = cs.foreground_points;
  s.background_points = background;
  s.invalid_points = points.size() - background - cs.foreground_points;  // by the model or the clusterer
  s.clusters_dropped_small = cs.clusters_dropped_small;
  s.clusters_dropped_large = cs.clusters_dropped_large;
  return result;
}

VehicleFix PerceptionPipeline::correct(const Detection& object, const AnnouncedVehicle& vehicle) const {
  return fix_vehicle(object.points, vehicle, lidar_position_, config_.fix);
}

}  // namespace rsu::perception
