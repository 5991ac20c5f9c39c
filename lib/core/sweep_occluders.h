// SPDX-License-Identifier: Apache-2.0
// What may hide part of a vehicle from the LiDAR: the other foreground objects of the same sweep (a car
// passing in front of a parked van, the next car of a queue) and the static scene's objects (a lamp post,
// a cabinet: the background's returns above the road). The fix takes a vehicle's points' end behind one
// of them for the shadow's edge, not the vehicle's (perception::LidarGeometry::occluders; README, Known
// shortfalls: occlusion).
//
// Each batch's detections are kept (their points' xy, when they were swept) for about a rotation; a
// released vehicle gets the points of every other detection swept within half a rotation of it that lie
// nearer the LiDAR than its farthest point, within its azimuth span (+ a margin), and the static points
// there. Its own detections are those whose points the gatherer copied into it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/vehicle_gatherer.h"
#include "lidar/point.h"
#include "perception/detection.h"

namespace rsu::core {

class SweepOccluders {
 public:
  // lidar_xy: the LiDAR in the map frame; rotation_period: how long a rotation lasts.
  SweepOccluders(const Eigen::Vector2d& lidar_xy, TimeNs rotation_period);

  // A batch's detections (before the gatherer takes them); forgets those swept more than a rotation
  // before the newest.
  void add(std::span<const perception::Detection> detections);
  // A background rotation (map frame): its returns at least `min_z` high (above the road) are the static
  // objects, kept on a 0.1 m grid.
  void add_static(std::span<const lidar::LidarPoint> points_in_map_frame, double min_z);
  // The static points of `from` (a reload that keeps the background), instead of these.
  void take_static(SweepOccluders&& from);
  // The points swept so far of clusters still open that a released one went ahead of
  // (perception::SweepClusterer::overtaken_open_points: map frame, one cluster each), in place of the
  // previous batch's. One of them is a vehicle's own when its fix is prepared before its release
  // (prepared_fixes.h): its first point tells it, as for a detection.
  void set_unfinished(std::span<const std::vector<lidar::LidarPoint>> clusters);
  // The other objects' points (xy, map frame) that may hide part of `held`.
  std::vector<Eigen::Vector2d> of(const HeldVehicle& held) const;

  void set_rotation_period(TimeNs rotation_period) { rotation_period_ = rotation_period; }
  std::size_t detections_kept() const { return kept_.size(); }
  std::size_t static_points() const { return static_cells_.size(); }

 private:
  struct Kept {
    std::vector<Eigen::Vector2d> xy;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();  // its first point, as the gatherer copies it
    TimeNs sweep_time = 0;
  };
  Eigen::Vector2d lidar_xy_;
  TimeNs rotation_period_;
  std::vector<Kept> kept_;
  std::vector<Kept> unfinished_;
  // The static points by azimuth about the LiDAR (one bucket a degree) and the grid cells they fill.
  std::vector<std::vector<Eigen::Vector2d>> static_by_azimuth_;
  std::unordered_set<std::uint64_t> static_cells_;
};

}  // namespace rsu::core
