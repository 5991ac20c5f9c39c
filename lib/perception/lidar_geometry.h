// SPDX-License-Identifier: Apache-2.0
// What a fix needs to know about the LiDAR that saw the vehicle: where it is, which elevations its lasers
// look at, how finely it samples azimuth, and where the road is. With it the fix can tell an edge of the
// vehicle from an edge of what the LiDAR could see: a car below a mast-mounted LiDAR is cut off where
// its lowest laser meets the car, not where the car ends (issue 12: "what the sensor can see of a box of
// known size from a known position").
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"

namespace rsu::perception {

// One question a computation asked of the occluders (LidarGeometry::occluded) and their answer.
struct OcclusionQuery {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double margin = 0.0;
  bool occluded = false;
};

struct LidarGeometry {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // map frame
  // The lasers' elevation angles (radians, up positive) for a level mount. Empty: unknown, every
  // direction counts as observed.
  std::vector<double> elevations_rad;
  double azimuth_step_rad = deg_to_rad(0.2);  // horizontal spacing of a laser's returns (VLP at 600 rpm)
  double ground_z = 0.0;                      // the road's height in the map frame
  // False when returns were lost near the vehicle (lost packets): where its points end says nothing
  // about where it ends, so no side counts as seen beyond them.
  bool complete_sweep = true;
  // The xy of other objects' returns near the vehicle (map frame; e.g. the foreground points of the
  // sweep that are not the vehicle's). Beyond one of them the LiDAR could not see whether the vehicle
  // goes on: its points' end there is the shadow's edge, not the vehicle's. Empty: nothing known to
  // occlude.
  std::vector<Eigen::Vector2d> occluders;
  // When set, occluded() appends each question and its answer here. A fix reads the occluders only
  // through occluded(), so it comes out the same, bit for bit, with any occluders that answer its
  // questions alike (answers_alike): a fix prepared while the sweep's other objects were still growing
  // holds at the release if none of the points added since lies where it looked (core/prepared_fixes.h).
  std::vector<OcclusionQuery>* occlusion_log = nullptr;

  Eigen::Vector2d xy() const { return position.head<2>(); }
  double height_above_ground() const { return position.z() - ground_z; }

  // Whether some laser would return from a vertical surface at horizontal range `range_m` between the
  // heights (above the road) `low` and `high`: the surface lies within the field of view and not
  // between two lasers' cones.
  bool sees_surface(double range_m, double low, double high) const;
  // Whether an occluder lies nearer than xy (by more than `margin`) within the angle `margin` subtends
  // at xy's range (at least two azimuth steps) of the line of sight to it.
  bool occluded(const Eigen::Vector2d& xy, double margin) const;
  // Whether `other_occluders`, in place of this geometry's, answer every question of `log` as recorded.
  bool answers_alike(std::span<const Eigen::Vector2d> other_occluders,
                     std::span<const OcclusionQuery> log) const;
  // Which laser (index into elevations_rad) returned a point at `p` (map frame): the one whose elevation
  // is nearest the point's as seen from the LiDAR; -1 when the elevations are unknown.
  int laser_of(const Eigen::Vector3d& p) const;
};

// laser_of for many points: the lasers sorted by elevation and the tangents of the midpoints between
// neighbours (a point's elevation is nearest a laser's exactly when its tangent lies between that laser's
// two midpoints), searched from the previous point's laser; points arrive firing by firing, so the next one
// is mostly a neighbour's. laser_of scans every laser with an atan2 per point: a dense sensor's 128 for
// each of a near car's thousands of points (issue 16).
class LaserLookup {
 public:
  explicit LaserLookup(const std::vector<double>& elevations_rad);
  // How many ranks there are (the lasers; 0 when the elevations are unknown).
  std::size_t count() const { return lasers_.size(); }
  // The rank by elevation of the laser nearest the elevation whose tangent is rise_over_run (the point's
  // height above the LiDAR over its horizontal range), searched from `hint` (a rank).
  std::size_t rank(double rise_over_run, std::size_t hint = 0) const {
    std::size_t r = std::min(hint, boundaries_.size());
    while (r > 0 && rise_over_run < boundaries_[r - 1])
      --r;
    while (r < boundaries_.size() && rise_over_run >= boundaries_[r])
      ++r;
    return r;
  }
  // That laser's index in elevations_rad (of lasers sharing one elevation, the first, as laser_of).
  int laser(std::size_t rank) const { return lasers_[rank]; }
  // rank for each of `points` seen from `origin` (map frame), searched from the previous point's; kNone
  // where a point is not finite or lies straight above or below the origin, and everywhere when the
  // elevations are unknown. The one way the fix tells the lasers' traces apart.
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> ranks(std::span<const Eigen::Vector3d> points,
                                 const Eigen::Vector3d& origin) const;

 private:
  std::vector<double> boundaries_;
  std::vector<int> lasers_;
};

}  // namespace rsu::perception
