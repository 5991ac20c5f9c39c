// The RSU's per-frame perception, as the paper runs it (Sec. 3-4): remove the static background, cluster
// what is left, fit a rectangle to each cluster (L-shape fitting). Association of clusters with the
// connected vehicles that announced their size is another step's job; it calls correct() per matched
// vehicle to turn the raw fit into a size-corrected fix (Algorithm 1 or the improved correction).
//
// Points come in the map frame (the caller applies the LiDAR mount pose) and keep their ring, azimuth and
// firing time; the LiDAR's map position is fixed for the pipeline's lifetime.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "lidar/point.h"
#include "perception/background_model.h"
#include "perception/euclidean_clustering.h"
#include "perception/ground_height_filter.h"
#include "perception/l_shape_fitting.h"
#include "perception/range_image_background.h"
#include "perception/reference_frame_background.h"
#include "perception/size_correction.h"

namespace rsu::perception {

enum class ClusteringMethod { reference, grid };
enum class CorrectionMethod { algorithm1, improved };

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

  ClusteringMethod clustering_method = ClusteringMethod::grid;
  // Autoware's tolerance and minimum, but a larger maximum: a car 10 m from a 32- or 128-ring LiDAR
  // returns several thousand points, and Autoware's 1000 would drop it whole.
  ClusteringConfig clustering{
      .tolerance_m = 0.7, .min_points = 10, .max_points = 20000, .distance = ClusterDistance::planar};

  LShapeFitConfig fit;
  CorrectionMethod correction_method = CorrectionMethod::improved;
  CorrectionConfig correction;
};

// One cluster: its points, its footprint and its rectangle fit.
struct DetectedObject {
  std::vector<std::uint32_t> point_indices;  // into the processed frame
  std::vector<Eigen::Vector2d> footprint;    // x, y of those points
  TimeNs sweep_time_ns = 0;                  // mean firing time: when the LiDAR swept it (DESIGN.md §3)
  RectangleFit fit;
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
  std::vector<DetectedObject> objects;
  PerceptionStats stats;
};

class PerceptionPipeline {
 public:
  PerceptionPipeline(const PerceptionConfig& config, const Eigen::Vector2d& lidar_xy);

  // A frame recorded without vehicles (map frame): becomes part of the reference frame, or trains the
  // range image. Unused by the ground-height method. Until one is added, every non-ground point is
  // foreground.
  void add_background_frame(std::span<const LidarPoint> points_in_map_frame);

  PerceptionResult process(std::span<const LidarPoint> points_in_map_frame) const;

  // The size-corrected fix of one object, for the vehicle matched to it.
  CorrectedPose correct(const DetectedObject& object, const VehicleSize& size,
                        const std::optional<YawPrior>& prior = std::nullopt) const;

  const PerceptionConfig& config() const { return config_; }
  const Eigen::Vector2d& lidar_xy() const { return lidar_xy_; }

 private:
  PerceptionConfig config_;
  Eigen::Vector2d lidar_xy_;
  BackgroundModel background_;
};

// The same correction as PerceptionPipeline::correct, for callers holding a fit and its points.
CorrectedPose correct(const RectangleFit& fit, std::span<const Eigen::Vector2d> cluster_xy,
                      const VehicleSize& size, const Eigen::Vector2d& lidar_xy,
                      const std::optional<YawPrior>& prior, const PerceptionConfig& config = {});

}  // namespace rsu::perception
