// SPDX-License-Identifier: Apache-2.0
#include "perception/reference_frame_background.h"

#include <vector>

namespace rsu::perception {
namespace {

std::vector<GridPoint> to_grid_points(std::span<const lidar::LidarPoint> points) {
  std::vector<GridPoint> out;
  out.reserve(points.size());
  for (const auto& p : points) {
    out.push_back({p.x, p.y, p.z});
  }
  return out;
}

}  // namespace

ReferenceFrameBackground::ReferenceFrameBackground(std::span<const lidar::LidarPoint> reference_points,
                                                   const ReferenceFrameBackgroundConfig& config)
    : radius_(static_cast<float>(config.match_radius_m)),
      // The cell is a hair larger than r so that a point at distance exactly r can never be two cells
      // away through float rounding of x / cell.
      grid_(to_grid_points(reference_points), radius_ * 1.001F, GridDims::spatial) {}

}  // namespace rsu::perception
