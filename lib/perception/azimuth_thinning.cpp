// SPDX-License-Identifier: Apache-2.0
#include "perception/azimuth_thinning.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace rsu::perception {
namespace {

// Each point's laser and azimuth column (LaserLookup::kNone: not finite, dropped).
struct Columns {
  std::vector<std::size_t> laser;
  std::vector<std::int64_t> column;
};

Columns columns_of(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar) {
  // The laser's rank by elevation (LaserLookup): a grouping, not an index into elevations_rad.
  const LaserLookup lookup(lidar.elevations_rad);
  Columns out{lookup.ranks(points, lidar.position), std::vector<std::int64_t>(points.size(), 0)};
  // Azimuths are measured from the first point's direction, so that a cluster across the +-pi line (the
  // LiDAR's -x axis) does not wrap; each laser's columns from its own first point.
  Eigen::Vector2d reference = Eigen::Vector2d::Zero();
  std::vector<double> first(lookup.count(), std::numeric_limits<double>::quiet_NaN());
  const double per_step = 1.0 / lidar.azimuth_step_rad;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t laser = out.laser[i];
    if (laser == LaserLookup::kNone)
      continue;
    const Eigen::Vector2d d = points[i].head<2>() - lidar.xy();
    if (reference.isZero())
      reference = d;
    // In float: its rounding (about 1e-7 of the angle) is far below a step (3e-3 rad).
    const double azimuth =
        static_cast<double>(std::atan2(static_cast<float>(reference.x() * d.y() - reference.y() * d.x()),
                                       static_cast<float>(reference.x() * d.x() + reference.y() * d.y())));
    if (std::isnan(first[laser]))
      first[laser] = azimuth;
    const double steps = (azimuth - first[laser]) * per_step;
    out.column[i] = static_cast<std::int64_t>(steps + (steps < 0.0 ? -0.5 : 0.5));  // the nearest
  }
  return out;
}

// Which columns of each laser's trace hold a point.
class Occupancy {
 public:
  Occupancy(const Columns& c, std::size_t lasers)
      : lo_(lasers, std::numeric_limits<std::int64_t>::max()),
        hi_(lasers, std::numeric_limits<std::int64_t>::min()),
        offset_(lasers, 0) {
    for (std::size_t i = 0; i < c.laser.size(); ++i) {
      if (c.laser[i] == LaserLookup::kNone)
        continue;
      lo_[c.laser[i]] = std::min(lo_[c.laser[i]], c.column[i]);
      hi_[c.laser[i]] = std::max(hi_[c.laser[i]], c.column[i]);
    }
    std::size_t size = 0;
    for (std::size_t l = 0; l < lasers; ++l) {
      offset_[l] = size;
      if (lo_[l] <= hi_[l])
        size += static_cast<std::size_t>(hi_[l] - lo_[l] + 1);
    }
    size_ = size;
  }
  // The table's size: every column of every laser's trace, from its first to its last.
  std::size_t size() const { return size_; }
  void fill(const Columns& c) {
    bits_.assign(size_, false);
    for (std::size_t i = 0; i < c.laser.size(); ++i) {
      if (c.laser[i] != LaserLookup::kNone)
        bits_[index(c.laser[i], c.column[i])] = true;
    }
  }
  bool occupied(std::size_t laser, std::int64_t column) const {
    return column >= lo_[laser] && column <= hi_[laser] && bits_[index(laser, column)];
  }
  std::int64_t first(std::size_t laser) const { return lo_[laser]; }

 private:
  std::size_t index(std::size_t laser, std::int64_t column) const {
    return offset_[laser] + static_cast<std::size_t>(column - lo_[laser]);
  }
  std::vector<std::int64_t> lo_, hi_;
  std::vector<std::size_t> offset_;
  std::size_t size_ = 0;
  std::vector<bool> bits_;
};

}  // namespace

AzimuthThinning thin_along_azimuth(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                                   std::size_t max_points) {
  AzimuthThinning out;
  const auto finite = static_cast<std::size_t>(
      std::count_if(points.begin(), points.end(), [](const Eigen::Vector3d& p) { return p.allFinite(); }));
  if (max_points == 0 || finite <= max_points || lidar.elevations_rad.empty() ||
      !(lidar.azimuth_step_rad > 0.0))
    return out;
  const Columns c = columns_of(points, lidar);
  Occupancy occupancy(c, lidar.elevations_rad.size());
  // Traces spread over far more columns than there are points are not dense along azimuth (and their
  // table would be large): left as they are.
  if (occupancy.size() > 64 * finite)
    return out;
  occupancy.fill(c);
  const auto stride = static_cast<std::int64_t>((finite + max_points - 1) / max_points);
  out.stride = static_cast<int>(stride);
  out.points.reserve(finite / static_cast<std::size_t>(stride) + lidar.elevations_rad.size() * 4);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t l = c.laser[i];
    const std::int64_t col = c.column[i];
    if (l == LaserLookup::kNone) {
      // Finite but straight above or below the LiDAR: no azimuth to thin by.
      if (points[i].allFinite())
        out.points.push_back(points[i]);
      continue;
    }
    // A trace's end or a break in it: no return in the next two columns on one side (one empty column
    // is the angle noise moving a return into its neighbour's column).
    const bool end = (!occupancy.occupied(l, col + 1) && !occupancy.occupied(l, col + 2)) ||
                     (!occupancy.occupied(l, col - 1) && !occupancy.occupied(l, col - 2));
    if (end || (col - occupancy.first(l)) % stride == 0)
      out.points.push_back(points[i]);
  }
  return out;
}

}  // namespace rsu::perception
