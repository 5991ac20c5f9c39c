// SPDX-License-Identifier: Apache-2.0
#include "core/sweep_position.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/angles.h"

namespace rsu::core {

SweepPosition::SweepPosition(const LidarMount& mount, double cluster_tolerance_m, double release_margin_deg,
                             const lidar::SweepGeometry& geometry)
    : mount_(mount),
      tolerance_m_(cluster_tolerance_m),
      release_margin_rad_(deg_to_rad(release_margin_deg)),
      rotation_hz_(geometry.rotation_hz) {
  follow(geometry);
}

void SweepPosition::follow(const lidar::SweepGeometry& geometry) {
  ring_offset_rad_ = geometry.ring_azimuth_offset_rad;
  min_offset_rad_ = 0.0;
  max_offset_rad_ = 0.0;
  if (!ring_offset_rad_.empty()) {
    const auto [lo, hi] = std::minmax_element(ring_offset_rad_.begin(), ring_offset_rad_.end());
    min_offset_rad_ = *lo;
    max_offset_rad_ = *hi;
  }
  lead_rad_ = geometry.azimuth_lead_rad;
}

double SweepPosition::lag_rad(const lidar::LidarPoint& newest) const {
  const double offset =
      newest.ring < ring_offset_rad_.size() ? ring_offset_rad_[newest.ring] : max_offset_rad_;
  return offset - min_offset_rad_ + lead_rad_ + release_margin_rad_;
}

void SweepPosition::advance(std::span<const lidar::LidarPoint> points) {
  if (!points.empty() && std::isfinite(points.back().azimuth_rad)) {
    latest_ = points.back();
    known_ = true;
  }
}

double SweepPosition::still_to_turn(std::span<const Eigen::Vector2d> outline, double beyond) const {
  // Beam azimuths clockwise from the sensor's +x, relative to the first outline point so that an
  // outline across the 0/360 deg cut needs no unwrapping.
  const double reference = mount_.beam_azimuth(outline.front());
  double ahead = 0.0;
  for (const Eigen::Vector2d& q : outline)
    ahead = std::max(ahead, wrap_angle(mount_.beam_azimuth(q) - reference));
  // Future firings lag the newest point by its laser's offset above the smallest, the lead and the
  // margin (file comment).
  const double target = reference + ahead + beyond + lag_rad(latest_);
  return wrap_angle_positive(target - static_cast<double>(latest_.azimuth_rad));
}

TimeNs SweepPosition::passed_time(std::span<const Eigen::Vector2d> outline) const {
  if (!known_ || outline.empty())
    return 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& q : outline)
    nearest = std::min(nearest, (q - mount_.xy()).norm());
  // The clusterer's rule: a point at range r is closed once the earliest future firing is asin(d / r)
  // past it.
  const double d = tolerance_m_;
  const double closing = nearest > d ? std::asin(d / nearest) : std::numbers::pi / 2.0;
  const double forward = still_to_turn(outline, closing);
  if (forward > std::numbers::pi)
    return latest_.time_ns;  // already behind the sweep
  const double radians_per_ns = 2.0 * std::numbers::pi / static_cast<double>(rotation_period_ns());
  return latest_.time_ns + static_cast<TimeNs>(forward / radians_per_ns);
}

bool SweepPosition::swept(std::span<const Eigen::Vector2d> outline) const {
  return known_ && !outline.empty() && still_to_turn(outline, 0.0) > std::numbers::pi;
}

}  // namespace rsu::core
