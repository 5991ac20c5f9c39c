// SPDX-License-Identifier: Apache-2.0
// Which fitted cluster is which announced vehicle. Each pair is gated by the Mahalanobis distance of
// the box centres and by size consistency, then ONE global minimum-cost assignment is solved over all
// pairs (Hungarian method, assignment.h), so two vehicles side by side are never swapped the way a
// greedy nearest-neighbour choice can swap them. Clusters of unregistered vehicles get nothing, and a
// registered vehicle with no cluster inside its gate gets nothing.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "perception/detection.h"
#include "tracking/vehicle_hypothesis.h"

namespace rsu::tracking {

struct AssociationConfig {
  // Chi-square gate on the 2-dof centre distance: 9.21 is the 99 % quantile. Leaving a vehicle
  // unmatched costs exactly this much, so any gated pair is preferred to no pair.
  double gate_chi2 = 9.21;
  // Centre noise of a box fitted to a well-seen vehicle (range noise, edge points, L-shape angle
  // step), added to the vehicle's own covariance.
  double fit_sigma_floor_m = 0.3;
  // Where faces are unseen the fitted box is short and its centre sits up to half the missing
  // extent towards the LiDAR (paper Section 3.1, Fig. 3): spread the gate by that along each box axis.
  bool inflate_for_unseen_extent = true;
  // Which announced dimension lies along which fitted edge: when the vehicle's yaw is known better
  // than this (1 sigma), the fitted edge nearer its heading is along its length, so the unseen extent
  // is (length - that edge) along the HEADING and (width - the other) across it. Otherwise both
  // pairings are allowed, along the fitted box's axes (its yaw is only known modulo 90 deg). Without
  // it a small cluster - a neighbour's near face, a fragment of a van behind - would widen the gate by
  // half a length across the vehicle, or along its own arbitrary yaw, and match an unconnected vehicle
  // in the next lane (issue 7, mis-association).
  double pairing_max_yaw_sigma_rad = 0.35;
  // A fitted box can exceed the announced one only by noise and a small angle error: longer edge
  // <= length * (1 + rel) + abs, shorter edge <= width * (1 + rel) + abs. Smaller is allowed
  // (occlusion, one visible face). Stops a merged cluster of two cars, or a bus, matching a car.
  double size_relative_tolerance = 0.2;
  double size_absolute_tolerance_m = 0.5;
};

enum class PairGate : std::uint8_t { kPass, kTooFar, kSizeMismatch, kInvalid };

struct PairCheck {
  PairGate verdict = PairGate::kInvalid;
  double distance_sq = 0.0;  // Mahalanobis distance squared of the centres (when computed)
};

// The gate for one detection-vehicle pair: the detection's fitted rectangle (L-shape fitting, before any
// size correction: its yaw may be off by 90 or 180 degrees, its edges short where faces are unseen)
// against the vehicle's predicted box. A rectangle that is not ok() or not finite is kInvalid.
PairCheck check_pair(const perception::RectangleFit& cluster, const VehicleHypothesis& vehicle,
                     const AssociationConfig& config = {});

struct AssociatedPair {
  std::size_t cluster = 0;  // index into the detections given
  std::size_t vehicle = 0;  // index into the vehicles given
  double distance_sq = 0.0;
};

struct AssociationResult {
  std::vector<AssociatedPair> pairs;  // ordered by cluster index
  std::vector<std::size_t> unmatched_clusters;
  std::vector<std::size_t> unmatched_vehicles;
  // Pair checks that failed, by reason (diagnostics).
  std::size_t pairs_too_far = 0;
  std::size_t pairs_size_mismatch = 0;
  std::size_t pairs_invalid = 0;
};

// Detections without a rectangle (too few points, degenerate) are not offered: they are listed in
// unmatched_clusters and left to the caller (a fragment of a vehicle may still join it by position).
AssociationResult associate(std::span<const perception::Detection> detections,
                            std::span<const VehicleHypothesis> vehicles,
                            const AssociationConfig& config = {});

}  // namespace rsu::tracking
