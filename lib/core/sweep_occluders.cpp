// SPDX-License-Identifier: Apache-2.0
#include "core/sweep_occluders.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/angles.h"
#include "lidar/point_eigen.h"

namespace rsu::core {
namespace {

// Beyond a vehicle's azimuth span the fix looks for occluders only as far as the probe just beyond its
// extreme point (box_axis.h: observation_probe_m past it, two azimuth steps of tolerance): a few degrees
// at the ranges a vehicle gets fixed.
constexpr double kAzimuthMarginRad = deg_to_rad(5.0);
// The static points are kept one per 0.1 m cell (a pole's returns of every laser and background rotation
// hide no more than one of them), in buckets of one degree of azimuth.
constexpr double kStaticCellM = 0.1;
constexpr int kAzimuthBuckets = 360;
constexpr double kBucketRad = 2.0 * kPi / kAzimuthBuckets;

constexpr double kInf = std::numeric_limits<double>::infinity();
// How far a pseudo-angle (below) may be from an edge's and still be decided by the angle itself: far more
// than their rounding (about 1e-15), far less than any object's extent (1e-9 is 1e-8 m at 20 m).
constexpr double kKeySlack = 1e-9;

// A number that orders directions (x, y) as atan2(y, x) does, over (-pi, pi], without an arctangent:
// in (-2, 2], 0 along +x.
double pseudo_angle(double x, double y) {
  const double sum = std::abs(x) + std::abs(y);
  if (sum == 0.0)
    return 0.0;
  const double p = y / sum;  // in [-1, 1]: the half-plane x >= 0
  if (x >= 0.0)
    return p;
  return y >= 0.0 ? 2.0 - p : -2.0 - p;
}

int azimuth_bucket(double azimuth) {
  const int b = static_cast<int>(std::floor((azimuth + kPi) / kBucketRad));
  return ((b % kAzimuthBuckets) + kAzimuthBuckets) % kAzimuthBuckets;
}

}  // namespace

SweepOccluders::SweepOccluders(const Eigen::Vector2d& lidar_xy, TimeNs rotation_period)
    : lidar_xy_(lidar_xy), rotation_period_(rotation_period), static_by_azimuth_(kAzimuthBuckets) {}

void SweepOccluders::add_static(std::span<const lidar::LidarPoint> points_in_map_frame, double min_z) {
  for (const lidar::LidarPoint& p : points_in_map_frame) {
    if (!(static_cast<double>(p.z) >= min_z) || !std::isfinite(p.x) || !std::isfinite(p.y))
      continue;
    const Eigen::Vector2d xy(p.x, p.y);
    const auto ix = static_cast<std::int32_t>(std::lround(xy.x() / kStaticCellM));
    const auto iy = static_cast<std::int32_t>(std::lround(xy.y() / kStaticCellM));
    const std::uint64_t cell =
        (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32) | static_cast<std::uint32_t>(iy);
    if (!static_cells_.insert(cell).second)
      continue;
    const Eigen::Vector2d r = xy - lidar_xy_;
    static_by_azimuth_[azimuth_bucket(std::atan2(r.y(), r.x()))].push_back(xy);
  }
}

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

void SweepOccluders::set_unfinished(std::span<const std::vector<lidar::LidarPoint>> clusters) {
  unfinished_.clear();
  for (const std::vector<lidar::LidarPoint>& points : clusters) {
    if (points.empty())
      continue;
    Kept k;
    k.xy.reserve(points.size());
    for (const lidar::LidarPoint& p : points)
      k.xy.emplace_back(p.x, p.y);
    const lidar::LidarPoint& first = points.front();  // as perception::Detection holds it
    k.first = lidar::position_of(first);
    unfinished_.push_back(std::move(k));
  }
}

void SweepOccluders::take_static(SweepOccluders&& from) {
  static_by_azimuth_ = std::move(from.static_by_azimuth_);
  static_cells_ = std::move(from.static_cells_);
}

std::vector<Eigen::Vector2d> SweepOccluders::of(const HeldVehicle& held) const {
  std::vector<Eigen::Vector2d> out;
  if (held.points.empty())
    return out;
  // The vehicle's azimuth span about its first point's direction (no wrap at +-pi) and farthest range.
  // The extreme directions are found by a pseudo-angle, which orders directions as their angle does, and
  // only their angles are computed (a dense sensor's near car holds 10-20 k points: an arctangent each
  // cost 0.3 ms, twice per fix, on the correction's path).
  const Eigen::Vector2d ref = held.points.front().head<2>() - lidar_xy_;
  const double ref_azimuth = std::atan2(ref.y(), ref.x());
  const auto angle_about_ref = [&](const Eigen::Vector2d& r) {
    return wrap_angle(std::atan2(r.y(), r.x()) - ref_azimuth);
  };
  Eigen::Vector2d least = ref, most = ref;
  double least_key = 0.0, most_key = 0.0, farthest_squared = 0.0;
  for (const Eigen::Vector3d& p : held.points) {
    const Eigen::Vector2d r = p.head<2>() - lidar_xy_;
    const double key = pseudo_angle(ref.dot(r), ref.x() * r.y() - ref.y() * r.x());
    if (key < least_key) {
      least_key = key;
      least = r;
    }
    if (key > most_key) {
      most_key = key;
      most = r;
    }
    farthest_squared = std::max(farthest_squared, r.squaredNorm());
  }
  const double lo = std::min(0.0, angle_about_ref(least));
  const double hi = std::max(0.0, angle_about_ref(most));
  const double farthest = std::sqrt(farthest_squared);
  // The span's edges as pseudo-angles about ref (no edge past +-pi: every angle about ref is within).
  const double from = lo - kAzimuthMarginRad, to = hi + kAzimuthMarginRad;
  const double key_from = from <= -kPi ? -kInf : pseudo_angle(std::cos(from), std::sin(from));
  const double key_to = to >= kPi ? kInf : pseudo_angle(std::cos(to), std::sin(to));
  const auto take_nearer_within_span = [&](std::span<const Eigen::Vector2d> points) {
    for (const Eigen::Vector2d& xy : points) {
      const Eigen::Vector2d r = xy - lidar_xy_;
      if (!(r.norm() < farthest))
        continue;
      // Most candidates are decided by their pseudo-angle (the other objects of a dense sensor's sweep
      // are tens of thousands of points, an arctangent each was a tenth of a millisecond per fix on the
      // correction's path); those within kKeySlack of an edge, or nearly opposite ref (where the angle
      // wraps), by their angle, as before: the points taken are the same.
      const double key = pseudo_angle(ref.dot(r), ref.x() * r.y() - ref.y() * r.x());
      if (key < key_from - kKeySlack || key > key_to + kKeySlack)
        continue;
      const bool inside = key > key_from + kKeySlack && key < key_to - kKeySlack;
      if (inside && std::abs(key) < 2.0 - kKeySlack) {
        out.push_back(xy);
        continue;
      }
      const double a = angle_about_ref(r);
      if (a >= from && a <= to)
        out.push_back(xy);
    }
  };
  const auto own = [&](const Kept& k) {
    return std::find(held.points.begin(), held.points.end(), k.first) != held.points.end();
  };
  const TimeNs when = held.sweep_time();
  for (const Kept& k : kept_) {
    if (std::abs(k.sweep_time - when) > rotation_period_ / 2 || own(k))
      continue;  // another rotation's, or one of its own detections
    take_nearer_within_span(k.xy);
  }
  for (const Kept& k : unfinished_) {
    if (!own(k))  // its own cluster, not released yet (a fix prepared ahead of its release)
      take_nearer_within_span(k.xy);
  }
  const int first = azimuth_bucket(ref_azimuth + lo - kAzimuthMarginRad);
  const int buckets = static_cast<int>(std::ceil((hi - lo + 2.0 * kAzimuthMarginRad) / kBucketRad)) + 1;
  for (int i = 0; i < std::min(buckets, kAzimuthBuckets); ++i)
    take_nearer_within_span(static_by_azimuth_[(first + i) % kAzimuthBuckets]);
  return out;
}

}  // namespace rsu::core
