// SPDX-License-Identifier: Apache-2.0
// Gathers each announced vehicle's detections across the batches of one rotation and holds the vehicle
// until the sweep has passed its predicted footprint: then it is released to be fixed from them all.
//
// Why gather. A vehicle far away and seen head-on breaks into fragments more than the clustering
// tolerance apart (bumper and front face low, cabin high, the hood between two rings), and the
// VLP-32C's per-laser azimuth offsets (+-4.2 deg, docs/design.md §2) close them in different batches. A
// fragment fitted as the whole vehicle is metres off, so a far vehicle's fix waits until the sweep has
// passed its whole predicted footprint (grown by its uncertainty) and the clusters that closed there.
// Near the LiDAR that footprint is passed about when its cluster closes: the wait is a few degrees.
//
// A batch's detections join vehicles in this order: the detection the global assignment gave a
// vehicle (association.h); then every other detection mostly inside one vehicle's grown footprint
// (grown_footprint.h); then, failing that, a fitted one passing the gate of a vehicle that got a
// detection in this batch.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/grown_footprint.h"
#include "core/rsu_core_config.h"
#include "core/sweep_position.h"
#include "perception/detection.h"
#include "tracking/association.h"
#include "tracking/vehicle_hypothesis.h"

namespace rsu::core {

// The detections gathered for one matched vehicle in this rotation, waiting for the sweep to pass it.
struct HeldVehicle {
  std::uint64_t vehicle_id = 0;
  std::vector<Eigen::Vector3d> points;  // union of the gathered detections' points, map frame
  TimeNs first_time = 0;                // sweep time of the first gathered detection
  TimeNs weighted_offset = 0;           // sum over points of (their detection's time - first_time)
  std::size_t parts = 0;                // detections gathered
  // The one gathered detection's thinning (perception::Detection::thinning): the fix of `points` takes
  // it; none once a second part is gathered (the union is thinned anew).
  std::optional<perception::AzimuthThinning> thinning;
  // The detection the global assignment gave this vehicle (the nearest in Mahalanobis distance if it
  // was given one in several batches), its range in `points`: what it is fixed from when the gathered
  // union is not one vehicle. The other parts may be a neighbour's (a car beside it, a van behind it)
  // lying inside the grown footprint: the largest of them is no better a guess.
  std::size_t assigned_begin = 0;
  std::size_t assigned_size = 0;  // 0: no detection was assigned, only gathered
  TimeNs assigned_time = 0;
  double assigned_distance_sq = 0.0;
  bool assigned_own = false;  // it lay in the footprint grown by the minimum margin + 1 sigma
  // Every detection gathered without being assigned lay mostly in the vehicle's lane (grown_footprint.h,
  // inside_lane): a vehicle whose announced clock is 0.8 s off fails the gate while its own cluster
  // still lies there; a neighbour's beside it does not.
  bool gathered_own = true;
  // Held after the vehicle was released with an assigned detection earlier in this rotation (fixed or
  // refused): what is gathered for it now lies beside or ahead of what was judged its own.
  bool after_assigned_release = false;
  bool far = false;  // beyond GatheringConfig::hold_beyond_m (held for its fragments)
  // A part released ahead of a nearer open cluster, or of a farther one reaching into the footprint
  // (GrownFootprint::tightly_overlaps; held for its fragments).
  bool ahead_of_open = false;
  TimeNs release_at = 0;  // firing time when the sweep has passed the footprint and its detections

  // The points' mean firing time: when the LiDAR swept the vehicle.
  TimeNs sweep_time() const { return first_time + weighted_offset / static_cast<TimeNs>(points.size()); }
  std::span<const Eigen::Vector3d> assigned_points() const {
    return std::span<const Eigen::Vector3d>(points).subspan(assigned_begin, assigned_size);
  }
};

class VehicleGatherer {
 public:
  VehicleGatherer(const GatheringConfig& gathering, const tracking::AssociationConfig& association,
                  const Eigen::Vector2d& lidar_xy);

  // One batch: its detections, the vehicles offered (predicted to the batch's sweep time) and the
  // association between them. Returns how many detections joined no vehicle.
  std::size_t gather(std::vector<perception::Detection>&& detections,
                     std::span<const tracking::VehicleHypothesis> vehicles,
                     const tracking::AssociationResult& association, const SweepPosition& sweep);
  // The held vehicles the sweep has passed (every one if `everything`: a whole rotation, the drain),
  // in the order they were first gathered.
  std::vector<HeldVehicle> release(bool everything, const SweepPosition& sweep);
  // The vehicles held now, in the order they were first gathered.
  std::span<const HeldVehicle> held() const { return held_; }

 private:
  // For each vehicle, the detections that join it (the assigned one first); counts the others.
  struct Members {
    std::vector<std::vector<std::size_t>> of_vehicle;
    std::vector<double> assigned_distance;  // per vehicle; < 0: no detection was assigned
    std::size_t unmatched = 0;
  };
  Members members(std::span<const perception::Detection> detections,
                  std::span<const tracking::VehicleHypothesis> vehicles,
                  std::span<const GrownFootprint> footprints,
                  const tracking::AssociationResult& association) const;
  HeldVehicle& held_for(std::uint64_t vehicle_id, TimeNs first_time, const SweepPosition& sweep);
  // When a vehicle that got detections in this batch may be released (file comment of the .cpp).
  TimeNs release_time(const HeldVehicle& held, const tracking::VehicleHypothesis& vehicle,
                      const GrownFootprint& footprint, std::span<const Eigen::Vector2d> outline, bool own,
                      const SweepPosition& sweep) const;

  GatheringConfig config_;
  tracking::AssociationConfig association_;
  Eigen::Vector2d lidar_xy_;
  std::vector<HeldVehicle> held_;
  // The vehicles released with an assigned detection within the last rotation: the sweep time of it.
  std::vector<std::pair<std::uint64_t, TimeNs>> released_assigned_;
};

}  // namespace rsu::core
