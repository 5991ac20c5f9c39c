// SPDX-License-Identifier: Apache-2.0
#include "core/sweep_occluders.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/angles.h"

namespace rsu::core {
namespace {

// Beyond a vehicle's azimuth span the fix looks for occluders only as far as the probe just beyond its
// extreme point (box_axis.h: observation_probe_m past it, two azimuth steps of tolerance): a few degrees
// at the ranges a vehicle gets fixed.
constexpr double kAzimuthMarginRad = deg_to_rad(5.0);

}  // namespace

SweepOccluders::SweepOccluders(const Eigen::Vector2d& lidar_xy, TimeNs rotation_period)
    : lidar_xy_(lidar_xy), rotation_period_(rotation_period) {}

void SweepOccluders::add(std::span<const perception::Detection> detections) {
  TimeNs newest = std::numeric_limits<TimeNs>::min();
  for (const perception::Detection& d : detections) {
    if (d.points.empty())
      continue;
    Kept k;
    k.xy.reserve(d.points.size());
    for (const Eigen::Vector3d& p : d.points)
      k.xy.push_back(p.head<2>());
    k.first = d.points.front();
    k.sweep_time = d.sweep_time_ns;
    newest = std::max(newest, d.sweep_time_ns);
    kept_.push_back(std::move(k));
  }
  if (newest == std::numeric_limits<TimeNs>::min())
    return;
  std::erase_if(kept_, [&](const Kept& k) { return k.sweep_time < newest - rotation_period_; });
}

std::vector<Eigen::Vector2d> SweepOccluders::of(const HeldVehicle& held) const {
  std::vector<Eigen::Vector2d> out;
  if (held.points.empty())
    return out;
  // The vehicle's azimuth span about its first point's direction (no wrap at +-pi) and farthest range.
  const Eigen::Vector2d ref = held.points.front().head<2>() - lidar_xy_;
  const double ref_azimuth = std::atan2(ref.y(), ref.x());
  double lo = 0.0, hi = 0.0, farthest = 0.0;
  for (const Eigen::Vector3d& p : held.points) {
    const Eigen::Vector2d r = p.head<2>() - lidar_xy_;
    const double a = wrap_angle(std::atan2(r.y(), r.x()) - ref_azimuth);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
    farthest = std::max(farthest, r.norm());
  }
  const TimeNs when = held.sweep_time();
  for (const Kept& k : kept_) {
    if (std::abs(k.sweep_time - when) > rotation_period_ / 2 ||
        std::find(held.points.begin(), held.points.end(), k.first) != held.points.end())
      continue;  // another rotation's, or one of its own detections
    for (const Eigen::Vector2d& xy : k.xy) {
      const Eigen::Vector2d r = xy - lidar_xy_;
      const double a = wrap_angle(std::atan2(r.y(), r.x()) - ref_azimuth);
      if (r.norm() < farthest && a >= lo - kAzimuthMarginRad && a <= hi + kAzimuthMarginRad)
        out.push_back(xy);
    }
  }
  return out;
}

}  // namespace rsu::core
