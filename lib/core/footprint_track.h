// SPDX-License-Identifier: Apache-2.0
// A connected vehicle's footprint tracked over rotations (issue 12, README "An elevated RSU"). From a mast
// 4-8 m up one laser crosses a car's roof and glasshouse and its ends, at bonnet and boot height, are not
// seen in that rotation: containment by the announced length is all that bounds the centre along the
// length, and the fix is withheld (position_unbounded). As the car moves its ends are seen from other
// ranges and angles in other rotations; what each rotation bounded is kept here and combined.
//
// What is kept, per vehicle: the hard interval the box centre was confined to along the fix's length
// axis (and how far across it, for turning it onto the next rotation's axis), the rotation's sweep time,
// yaw and the announced size. A fix whose centre lies in an interval (box_axis.h) bounds it by that
// interval plus 3 sigma of its other terms (noise, shape, a yaw error's turn); any other fix by 3 sigma of
// its length-axis variance, at least min_bound_half_m. The interval is carried to the next sweep time by
// the vehicle's own motion (its announcement's speed and yaw rate, CTRV), widened by a conservative
// bound on that motion's error (speed, acceleration since the announcement, heading), and intersected
// with the new rotation's: never multiplied as independent (the rotations share geometry), only cut.
// An interval-placed fix is re-centred on the intersection, its length-axis variance that of a uniform
// error over it, when that is smaller than its own; withheld as unbounded, it is sent once that brings
// it under the position cap.
//
// The chain is broken (the track forgotten, counted) by a gap of more than max_gap_rotations, a yaw
// change the announced yaw rate does not explain, a re-announced size, a fix from clusters the
// association did not give the vehicle, a fix refused for any other reason, a vehicle without an
// announced speed, and the mount check stopping the fixes. An empty intersection says one of the bounds
// was wrong: the fix is withheld (track_conflict) and the track forgotten.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <utility>

#include <Eigen/Core>

#include "common/time.h"
#include "core/gathered_fix.h"
#include "core/lidar_stats.h"
#include "tracking/vehicle_hypothesis.h"
#include "v2i/messages.h"

namespace rsu::core {

// FootprintTrackConfig: core/rsu_core_config.h.

// The part of a fix's box centre bounded along its length axis, in the map frame: centre + s * axis with
// s in [lo, hi], and at most across_half_m off the axis.
struct FootprintBound {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();
  double lo = 0.0;
  double hi = 0.0;
  double across_half_m = 0.0;
};

// The bound a fix's own rotation gives (the correction's pose, covariance and length-axis evidence).
FootprintBound bound_of(const perception::CorrectedPose& fix, const FootprintTrackConfig& config);

// Where `bound`, carried by `motion` (its centre moved, map frame) with an error of at most along_error_m
// along its axis and across_error_m across it, lies along `direction` (a unit vector) from `origin`: the
// interval (lo, hi) of its projection.
std::pair<double, double> carried_interval(const FootprintBound& bound, const Eigen::Vector2d& motion,
                                           double along_error_m, double across_error_m,
                                           const Eigen::Vector2d& origin, const Eigen::Vector2d& direction);

class FootprintTracks {
 public:
  explicit FootprintTracks(const FootprintTrackConfig& config = {}) : config_(config) {}

  // Combines `fix` (of vehicle a.vehicle_id, released now) with what earlier rotations bounded, and keeps
  // what it bounds. assigned: fixed from clusters the association gave the vehicle. max_sigma_m: the
  // position sigma a fix may state (perception::max_position_sigma_m). Counts into `stats`.
  void combine(GatheredFix& fix, const v2i::VehicleAnnouncement& a, bool assigned, TimeNs rotation_period,
               double max_sigma_m, const tracking::HypothesisConfig& hypothesis, LidarStats& stats);
  // Forgets every vehicle's track (the mount check stopped the fixes).
  void reset(LidarStats& stats);
  // Forgets the tracks not combined since before `oldest`.
  void prune(TimeNs oldest);
  std::size_t size() const { return tracks_.size(); }

 private:
  struct Track {
    FootprintBound bound;
    TimeNs time = 0;
    double yaw = 0.0;
    double yaw_sigma = 0.0;
    v2i::BoxSize size;
  };
  // Whether `track` can be carried to this fix's rotation (the chain unbroken).
  bool chained(const Track& track, const GatheredFix& fix, const v2i::VehicleAnnouncement& a,
               TimeNs rotation_period) const;

  FootprintTrackConfig config_;
  std::unordered_map<std::uint64_t, Track> tracks_;
};

}  // namespace rsu::core
