// SPDX-License-Identifier: Apache-2.0
#include "perception/background_model.h"

namespace rsu::perception {

BackgroundModel::BackgroundModel(const BackgroundModelConfig& config, const Eigen::Vector2d& lidar_xy)
    : config_(config), ground_(config.ground), range_image_(lidar_xy, config.range_image) {}

void BackgroundModel::add_background_frame(std::span<const lidar::LidarPoint> points) {
  ++frames_;
  switch (config_.method) {
    case BackgroundMethod::ground_height:
      return;
    case BackgroundMethod::reference_frame:
      for (const lidar::LidarPoint& p : points) {
        // Reference points the prefilter would drop anyway only slow the look-ups down.
        if (!config_.ground_prefilter || ground_.classify(p) == PointClass::foreground) {
          reference_points_.push_back(p);
        }
      }
      reference_.emplace(reference_points_, config_.reference_frame);
      return;
    case BackgroundMethod::range_image:
      range_image_.add_training_frame(points);
      return;
  }
}

PointClass BackgroundModel::classify(const lidar::LidarPoint& p) const {
  if (config_.method == BackgroundMethod::ground_height || config_.ground_prefilter) {
    const PointClass c = ground_.classify(p);
    if (c != PointClass::foreground || config_.method == BackgroundMethod::ground_height) {
      return c;
    }
  }
  switch (config_.method) {
    case BackgroundMethod::ground_height:
      break;
    case BackgroundMethod::reference_frame:
      if (!reference_) {
        return is_finite_point(p) ? PointClass::foreground : PointClass::invalid;
      }
      return reference_->classify(p);
    case BackgroundMethod::range_image:
      return range_image_.classify(p);
  }
  return PointClass::invalid;
}

}  // namespace rsu::perception
