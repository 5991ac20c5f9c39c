// SPDX-License-Identifier: Apache-2.0
// The static background, whichever way it is modelled (paper Sec. 3.1 and 4.1), as one per-point
// decision: the ground prefilter first (far ground returns at grazing incidence move by metres with
// beam-angle noise, ground_height_filter.h), then the configured model. Used on whole frames by the
// perception pipeline and point by point, as packets arrive, by the RSU's sector processing.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidar/point.h"
#include "perception/foreground.h"
#include "perception/ground_height_filter.h"
#include "perception/range_image_background.h"
#include "perception/reference_frame_background.h"

namespace rsu::perception {

enum class BackgroundMethod { ground_height, reference_frame, range_image };

struct BackgroundModelConfig {
  BackgroundMethod method = BackgroundMethod::range_image;
  bool ground_prefilter = true;  // also applied before the reference-frame and range-image tests
  GroundHeightFilterConfig ground;
  ReferenceFrameBackgroundConfig reference_frame;
  RangeImageBackgroundConfig range_image;

  bool operator==(const BackgroundModelConfig&) const = default;
};

class BackgroundModel {
 public:
  BackgroundModel(const BackgroundModelConfig& config, const Eigen::Vector2d& lidar_xy);

  // A frame recorded without vehicles (map frame): extends the reference frame or trains the range
  // image; the ground-height method needs none. Until one is added, every non-ground point is foreground.
  void add_background_frame(std::span<const lidar::LidarPoint> points_in_map_frame);
  int background_frames() const { return frames_; }

  PointClass classify(const lidar::LidarPoint& p) const;
  ForegroundSelection select_foreground(std::span<const lidar::LidarPoint> points) const {
    return perception::select_foreground(points, [this](const lidar::LidarPoint& p) { return classify(p); });
  }

 private:
  BackgroundModelConfig config_;
  GroundHeightFilter ground_;
  RangeImageBackground range_image_;
  std::vector<lidar::LidarPoint> reference_points_;
  std::optional<ReferenceFrameBackground> reference_;
  int frames_ = 0;
};

}  // namespace rsu::perception
