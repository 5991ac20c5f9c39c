// SPDX-License-Identifier: Apache-2.0
// What may hide part of a vehicle from the LiDAR: the other foreground objects of the same sweep (a car
// passing in front of a parked van, the next car of a queue). The fix takes a vehicle's points' end
// behind one of them for the shadow's edge, not the vehicle's (perception::LidarGeometry::occluders;
// README, Known shortfalls: occlusion).
//
// Each batch's detections are kept (their points' xy, when they were swept) for about a rotation; a
// released vehicle gets the points of every other detection swept within half a rotation of it that lie
// nearer the LiDAR than its farthest point, within its azimuth span (+ a margin). Its own detections are
// those whose points the gatherer copied into it.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/vehicle_gatherer.h"
#include "perception/detection.h"

namespace rsu::core {

class SweepOccluders {
 public:
  // lidar_xy: the LiDAR in the map frame; rotation_period: how long a rotation lasts.
  SweepOccluders(const Eigen::Vector2d& lidar_xy, TimeNs rotation_period);

  // A batch's detections (before the gatherer takes them); forgets those swept more than a rotation
  // before the newest.
  void add(std::span<const perception::Detection> detections);
  // The other objects' points (xy, map frame) that may hide part of `held`.
  std::vector<Eigen::Vector2d> of(const HeldVehicle& held) const;

  void set_rotation_period(TimeNs rotation_period) { rotation_period_ = rotation_period; }
  std::size_t detections_kept() const { return kept_.size(); }

 private:
  struct Kept {
    std::vector<Eigen::Vector2d> xy;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();  // its first point, as the gatherer copies it
    TimeNs sweep_time = 0;
  };
  Eigen::Vector2d lidar_xy_;
  TimeNs rotation_period_;
  std::vector<Kept> kept_;
};

}  // namespace rsu::core
