// SPDX-License-Identifier: Apache-2.0
// An announced vehicle's predicted footprint grown by its uncertainty (GatheringConfig): where the
// detections of that vehicle may lie when its pose, carried to the sweep time, is uncertain.
#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rsu_core_config.h"
#include "perception/detection.h"
#include "tracking/vehicle_hypothesis.h"

namespace rsu::core {

class GrownFootprint {
 public:
  // The announced box at the predicted pose, every corner moved out by footprint_sigmas standard
  // deviations of the predicted centre (largest axis) and of the yaw (at the corners), clamped to
  // [min_margin_m, max_margin_m].
  GrownFootprint(const tracking::VehicleHypothesis& vehicle, const GatheringConfig& config);

  // Share of the detection's points inside the grown footprint (0 for a detection without points).
  double inside_fraction(const perception::Detection& detection) const;
  // Whether at least min_inside_fraction of the detection's points lie in the footprint grown by the
  // minimum margin and one sigma of the predicted centre only: the vehicle's own, rather than a
  // neighbour's inside the wider margin (a vehicle that knows it is lost may be found farther off).
  bool tightly_inside(const perception::Detection& detection) const;
  // The same with the tight margin across the vehicle only and the grown one along it: within its lane.
  // A vehicle's timing or speed error moves its prediction along its heading (an announcement 0.8 s
  // stale is predicted 2.4 m ahead), never sideways; a neighbour side by side is off across it.
  bool inside_lane(const perception::Detection& detection) const;

  const std::array<Eigen::Vector2d, 4>& corners() const { return corners_; }
  // The corners of the footprint grown by the minimum margin and one sigma (as tightly_inside).
  const std::array<Eigen::Vector2d, 4>& tight_corners() const { return tight_corners_; }
  // Whether `box` (map frame, axis-aligned) shares any place with the footprint grown by the minimum
  // margin and one sigma only (as tightly_inside): where a fragment of the vehicle itself may lie.
  bool tightly_overlaps(const Eigen::AlignedBox2d& box) const;

 private:
  double fraction_inside(const perception::Detection& detection, const Eigen::Vector2d& half) const;

  Eigen::Vector2d centre_;
  double yaw_;
  Eigen::Vector2d half_;        // grown half extents along and across the vehicle
  Eigen::Vector2d tight_half_;  // the same grown by the minimum margin and one centre sigma
  Eigen::Vector2d lane_half_;   // grown along, tight across
  double min_inside_fraction_;
  std::array<Eigen::Vector2d, 4> corners_;
  std::array<Eigen::Vector2d, 4> tight_corners_;
};

}  // namespace rsu::core
