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
  // The laser's rank by elevation (LaserLookup, as LaserLookup::ranks gives it, in the same pass): a
  // grouping, not an index into elevations_rad.
  const LaserLookup lookup(lidar.elevations_rad);
  Columns out{std::vector<std::size_t>(points.size(), LaserLookup::kNone),
              std::vector<std::int64_t>(points.size(), 0)};
  // Azimuths are measured from the first point's direction, so that a cluster across the +-pi line (the
  // LiDAR's -x axis) does not wrap; each laser's columns from its own first point.
  const auto valid = [&](const Eigen::Vector3d& p) {
    return p.allFinite() && (p.head<2>() - lidar.xy()).squaredNorm() > 0.0;
  };
  const auto first_valid = std::find_if(points.begin(), points.end(), valid);
  if (first_valid == points.end())
    return out;
  const Eigen::Vector2d reference = first_valid->head<2>() - lidar.xy();
  // The angles in a pass of their own: its iterations are independent (a long chain of arithmetic
  // each), where the pass below waits on the laser search's hint.
  std::vector<double> azimuth(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d d = points[i].head<2>() - lidar.xy();
    azimuth[i] = azimuth_angle(reference.x() * d.y() - reference.y() * d.x(), reference.dot(d));
  }
  std::vector<double> first(lookup.count(), std::numeric_limits<double>::quiet_NaN());
  const double per_step = 1.0 / lidar.azimuth_step_rad;
  std::size_t hint = 0;  // points arrive firing by firing: the next is mostly a neighbour's laser
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    if (!valid(p))
      continue;
    const double run = (p.head<2>() - lidar.xy()).norm();
    hint = lookup.rank((p.z() - lidar.position.z()) / run, hint);
    const std::size_t laser = hint;
    out.laser[i] = laser;
    if (std::isnan(first[laser]))
      first[laser] = azimuth[i];
    const double steps = (azimuth[i] - first[laser]) * per_step;
    out.column[i] = static_cast<std::int64_t>(steps + (steps < 0.0 ? -0.5 : 0.5));  // the nearest
  }
  return out;
}

// Which columns of each laser's trace hold a point: a byte per column from two before the trace's first
// to two after its last, so that a trace's points and their neighbours two columns either side need no
// bounds check.
class Occupancy {
 public:
  static constexpr std::int64_t kMargin = 2;

  Occupancy(const Columns& c, std::size_t lasers)
      : lo_(lasers, std::numeric_limits<std::int64_t>::max()),
        hi_(lasers, std::numeric_limits<std::int64_t>::min()),
        base_(lasers, 0) {
    for (std::size_t i = 0; i < c.laser.size(); ++i) {
      if (c.laser[i] == LaserLookup::kNone)
        continue;
      lo_[c.laser[i]] = std::min(lo_[c.laser[i]], c.column[i]);
      hi_[c.laser[i]] = std::max(hi_[c.laser[i]], c.column[i]);
    }
    for (std::size_t l = 0; l < lasers; ++l) {
      if (lo_[l] > hi_[l])
        continue;
      // Column col of laser l at base_[l] + col (as unsigned arithmetic wraps, for any lo_).
      base_[l] = bytes_size_ + static_cast<std::size_t>(kMargin) - static_cast<std::size_t>(lo_[l]);
      columns_ += static_cast<std::size_t>(hi_[l] - lo_[l] + 1);
      bytes_size_ += static_cast<std::size_t>(hi_[l] - lo_[l] + 1 + 2 * kMargin);
    }
  }
  // Every column of every laser's trace, from its first to its last.
  std::size_t columns() const { return columns_; }
  void fill(const Columns& c) {
    bytes_.assign(bytes_size_, 0);
    for (std::size_t i = 0; i < c.laser.size(); ++i) {
      if (c.laser[i] != LaserLookup::kNone)
        bytes_[index(c.laser[i], c.column[i])] = 1;
    }
  }
  // Column `column` of laser `laser`, within kMargin of its trace's first and last.
  bool occupied(std::size_t laser, std::int64_t column) const { return bytes_[index(laser, column)] != 0; }
  std::int64_t first(std::size_t laser) const { return lo_[laser]; }

 private:
  std::size_t index(std::size_t laser, std::int64_t column) const {
    return base_[laser] + static_cast<std::size_t>(column);
  }
  std::vector<std::int64_t> lo_, hi_;
  std::vector<std::size_t> base_;
  std::size_t columns_ = 0, bytes_size_ = 0;
  std::vector<std::uint8_t> bytes_;
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
  if (occupancy.columns() > 64 * finite)
    return out;
  occupancy.fill(c);
  const auto stride = static_cast<std::uint32_t>((finite + max_points - 1) / max_points);
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
    // The column's place along the trace fits 32 bits (the table holds it): a cheaper division.
    if (end || static_cast<std::uint32_t>(col - occupancy.first(l)) % stride == 0)
      out.points.push_back(points[i]);
  }
  return out;
}

}  // namespace rsu::perception
