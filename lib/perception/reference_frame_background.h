// SPDX-License-Identifier: Apache-2.0
// Background removal (b), the paper's method (Sec. 4.1): a reference frame is recorded while no vehicle
// is in view; a point of a later frame is foreground when no reference point lies within
// `match_radius_m` of it. The paper finds the nearest reference point with a k-d tree; a hash grid of
// cell size r answers the same yes/no question exactly in O(1) (see point_hash_grid.h).
//
// Radius choice (default 0.3 m, the paper does not state one): a background point must find a reference
// point although the two frames sample the surface at different azimuths and with independent noise.
// On a surface facing the LiDAR at range R the reference samples are R * 0.2 deg apart (VLP azimuth
// step, docs/design.md §2), so the worst offset is half that, 0.09 m at 50 m; the noise difference of two
// returns has sigma sqrt(2) * sqrt(0.02^2 + (R * 0.001)^2) = 0.08 m at 50 m. 0.09 + 2.5 * 0.08 ~ 0.3 m.
// A vehicle loses only the points within 0.3 m of a reference surface (tyre bottoms next to the road),
// which the ground prefilter removes anyway. Several reference frames may be concatenated: the denser
// the reference, the smaller the sampling offset.
#pragma once

#include <span>

#include "lidar/point.h"
#include "perception/foreground.h"
#include "perception/point_hash_grid.h"

namespace rsu::perception {

struct ReferenceFrameBackgroundConfig {
  double match_radius_m = 0.3;  // see the file comment

  bool operator==(const ReferenceFrameBackgroundConfig&) const = default;
};

class ReferenceFrameBackground {
 public:
  // reference_points: one or more frames without vehicles, in the map frame. Non-finite points are
  // ignored (counted in skipped_reference_points()).
  explicit ReferenceFrameBackground(std::span<const lidar::LidarPoint> reference_points,
                                    const ReferenceFrameBackgroundConfig& config = {});

  PointClass classify(const lidar::LidarPoint& p) const {
    const GridPoint q{p.x, p.y, p.z};
    if (!grid_.in_domain(q)) {
      return PointClass::invalid;
    }
    return grid_.any_within(q, radius_) ? PointClass::background : PointClass::foreground;
  }

  ForegroundSelection select_foreground(std::span<const lidar::LidarPoint> points) const {
    return perception::select_foreground(points, [this](const lidar::LidarPoint& p) { return classify(p); });
  }

  std::size_t reference_point_count() const { return grid_.points().size(); }
  std::size_t skipped_reference_points() const { return grid_.skipped(); }

 private:
  float radius_;
  PointHashGrid grid_;
};

}  // namespace rsu::perception
