// SPDX-License-Identifier: Apache-2.0
#include "eval/pilot/outline_observability.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rsu::eval {
namespace {

// One axis of the footprint: the points' coordinates along it and its extent.
bool axis_pinned(std::span<const double> along, double extent, const OutlineObservabilityConfig& config) {
  if (along.empty())
    return false;
  const double edge = 0.5 * extent - config.tolerance_m;
  std::size_t low = 0, high = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double a : along) {
    low += a <= -edge;
    high += a >= edge;
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  return low >= config.min_points || high >= config.min_points ||
         hi - lo >= extent - 2.0 * config.tolerance_m;
}

}  // namespace

OutlineObservability observe_outline(std::span<const Eigen::Vector3d> points, const Pose2& truth,
                                     double length, double width, const OutlineObservabilityConfig& config) {
  const Eigen::Vector2d axis(std::cos(truth.yaw), std::sin(truth.yaw));
  const Eigen::Vector2d across(-axis.y(), axis.x());
  std::vector<double> u, v;
  u.reserve(points.size());
  v.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite())
      continue;
    const Eigen::Vector2d d(p.x() - truth.x, p.y() - truth.y);
    u.push_back(d.dot(axis));
    v.push_back(d.dot(across));
  }
  OutlineObservability out;
  out.length_pinned = axis_pinned(u, length, config);
  out.width_pinned = axis_pinned(v, width, config);
  return out;
}

}  // namespace rsu::eval
