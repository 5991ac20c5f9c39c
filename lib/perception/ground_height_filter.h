// SPDX-License-Identifier: Apache-2.0
// Background removal (a): the pilot experiment's filter (paper Sec. 3.1: "we filtered out zero-height
// points"). In an otherwise empty scene everything standing above the ground is the vehicle, so a point
// is foreground when it is higher than a small threshold above the ground plane. Also used as a cheap
// prefilter before the other methods: far ground returns at grazing incidence move by metres with
// beam-angle noise and would otherwise survive a nearest-neighbour or range test.
#pragma once

#include "lidar/point.h"
#include "perception/foreground.h"

namespace rsu::perception {

struct GroundHeightFilterConfig {
  double ground_z = 0.0;    // height of the (horizontal) ground plane in the map frame, metres
  double min_height = 0.2;  // points lower than ground_z + min_height are ground; the pilot's default

  bool operator==(const GroundHeightFilterConfig&) const = default;
};

class GroundHeightFilter {
 public:
  explicit GroundHeightFilter(const GroundHeightFilterConfig& config = {})
      : min_z_(static_cast<float>(config.ground_z + config.min_height)) {}

  PointClass classify(const lidar::LidarPoint& p) const {
    if (!is_finite_point(p)) {
      return PointClass::invalid;
    }
    return p.z < min_z_ ? PointClass::background : PointClass::foreground;
  }

  ForegroundSelection select_foreground(std::span<const lidar::LidarPoint> points) const {
    return perception::select_foreground(points, [this](const lidar::LidarPoint& p) { return classify(p); });
  }

 private:
  float min_z_;
};

}  // namespace rsu::perception
