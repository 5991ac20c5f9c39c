// Point-by-point background removal for the RSU's sector processing. The perception pipeline
// (perception/pipeline.h) removes the background of a whole frame inside process(); the RSU needs the
// same decision per packet, as points arrive, so that clustering can run on a vehicle as soon as the
// sweep has passed it (sweep_clusterer.h). This class applies the SAME models, chained the same way
// (ground prefilter, then the configured model): perception::PerceptionConfig selects them.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidar/point.h"
#include "perception/foreground.h"
#include "perception/ground_height_filter.h"
#include "perception/pipeline.h"
#include "perception/range_image_background.h"
#include "perception/reference_frame_background.h"

namespace rsu::core {

class ForegroundFilter {
 public:
  ForegroundFilter(const perception::PerceptionConfig& config, const Eigen::Vector2d& lidar_xy);

  // One frame without vehicles, in the map frame (trains the range image, or extends the reference
  // frame; the ground-height method needs none).
  void add_background_frame(std::span<const LidarPoint> points_in_map_frame);
  int background_frames() const { return frames_; }

  perception::PointClass classify(const LidarPoint& p) const;

 private:
  perception::PerceptionConfig config_;
  perception::GroundHeightFilter ground_;
  perception::RangeImageBackground range_image_;
  std::vector<LidarPoint> reference_points_;
  std::optional<perception::ReferenceFrameBackground> reference_;
  int frames_ = 0;
};

}  // namespace rsu::core
