// SPDX-License-Identifier: Apache-2.0
#include "perception/detection.h"

#include "lidar/point_eigen.h"

namespace rsu::perception {
namespace {

// `point_at(k)` for k < n gives the k-th point of the detection.
template <typename PointAt>
Detection detect_points(std::size_t n, PointAt point_at, const Eigen::Vector2d& lidar_xy,
                        const LShapeFitConfig& config, const FitThinning& thinning = {}) {
  Detection d;
  d.points.reserve(n);
  std::vector<Eigen::Vector2d> footprint;
  footprint.reserve(n);
  const TimeNs t0 = point_at(0).time_ns;
  TimeNs offset_sum = 0;  // relative to t0: a detection spans well under a second, so no overflow
  for (std::size_t k = 0; k < n; ++k) {
    const lidar::LidarPoint& p = point_at(k);
    d.points.push_back(lidar::position_of(p));
    footprint.emplace_back(static_cast<double>(p.x), static_cast<double>(p.y));
    offset_sum += p.time_ns - t0;
  }
  d.sweep_time_ns = t0 + offset_sum / static_cast<TimeNs>(n);
  if (thinning.lidar != nullptr) {
    d.thinning = thin_along_azimuth(d.points, *thinning.lidar, thinning.above_points);
    if (d.thinning->stride > 1) {
      footprint.clear();
      for (const Eigen::Vector3d& p : d.thinning->points)
        footprint.emplace_back(p.x(), p.y());
    }
  }
  d.fit = fit_rectangle(footprint, lidar_xy, config);
  return d;
}

}  // namespace

Detection detect(std::span<const lidar::LidarPoint> points, const Eigen::Vector2d& lidar_xy,
                 const LShapeFitConfig& config, const FitThinning& thinning) {
  return detect_points(
      points.size(), [&](std::size_t k) -> const lidar::LidarPoint& { return points[k]; }, lidar_xy, config,
      thinning);
}

Detection detect(std::span<const lidar::LidarPoint> frame, std::span<const std::uint32_t> indices,
                 const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& config) {
  return detect_points(
      indices.size(), [&](std::size_t k) -> const lidar::LidarPoint& { return frame[indices[k]]; }, lidar_xy,
      config);
}

}  // namespace rsu::perception
