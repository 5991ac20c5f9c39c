// SPDX-License-Identifier: Apache-2.0
// A released vehicle's fix (vehicle_gatherer.h): from which of its gathered points, with its announced
// size and heading, through perception::fix_vehicle with rsud's configuration, and the checks a fix
// must pass before a correction may go out.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/lidar_mount.h"
#include "core/lidar_stats.h"
#include "core/rsu_core_config.h"
#include "core/vehicle_gatherer.h"
#include "lidar/point.h"
#include "perception/detection.h"
#include "perception/lidar_geometry.h"
#include "perception/vehicle_fix.h"
#include "v2i/messages.h"

namespace rsu::core {

enum class GatheredFixOutcome {
  fixed,
  doubtful_cluster,     // a near vehicle held for a doubtful assigned cluster got none of its own
  no_assigned_cluster,  // its parts were only gathered, none assigned: not all its own, or not one vehicle
  fit_failed,           // no rectangle could be fitted
  out_of_coverage,      // beyond RsuCoreConfig::coverage_radius_m
  inconsistent,         // the known-size box contradicts the points, or they do not place it
  correction_failed,    // the size correction refused it for another reason
  // its bound contradicts what earlier rotations bounded (footprint_track.h): one of them is wrong
  track_conflict,
};

struct GatheredFix {
  GatheredFixOutcome outcome = GatheredFixOutcome::fit_failed;
  perception::VehicleFix fix;
  TimeNs sweep_time = 0;                // mean firing time of the points it was fixed (or held) from
  std::size_t fragments_merged = 0;     // extra parts fixed with the assigned one
  std::size_t fragments_unmatched = 0;  // parts left out (someone else's)

  bool ok() const { return outcome == GatheredFixOutcome::fixed; }
};

// Adds what became of one released vehicle to the LiDAR counters.
void count(const GatheredFix& fix, LidarStats& stats);

class GatheredVehicleFixer {
 public:
  GatheredVehicleFixer(const RsuCoreConfig& config, const LidarMount& mount);

  // The fix of `held` with what the vehicle announced (`a`): from the whole gathered union if it is
  // one vehicle of the announced size; otherwise from the detection the assignment gave it alone.
  // lost_nearby: LiDAR packets were lost while the sweep passed it (no side of it counts as seen);
  // occluders: the other objects' points that may hide part of it (sweep_occluders.h); what the fix
  // asked of them is appended to `occlusion_queries` when given (answers_alike).
  GatheredFix fix(const HeldVehicle& held, const v2i::VehicleAnnouncement& a, bool lost_nearby = false,
                  std::vector<Eigen::Vector2d> occluders = {},
                  std::vector<perception::OcclusionQuery>* occlusion_queries = nullptr) const;
  // Whether `occluders` answer a fix's `occlusion_queries` as its own did: then that fix is the one
  // these give, bit for bit (perception::LidarGeometry::occlusion_log).
  bool answers_alike(std::span<const Eigen::Vector2d> occluders,
                     std::span<const perception::OcclusionQuery> occlusion_queries) const {
    return lidar_.answers_alike(occluders, occlusion_queries);
  }
  // A cluster's rectangle for association (perception::detect), fitted as its fix is (thinned alike).
  perception::Detection detect(std::span<const lidar::LidarPoint> points) const;

 private:
  // The vehicle's fix from its points swept at `sweep_time`, with its announced size and its announced
  // heading carried to that time as the yaw prior; `thinning`: the points' as detect made it, if known.
  perception::VehicleFix fix_announced(std::span<const Eigen::Vector3d> points,
                                       const perception::AzimuthThinning* thinning,
                                       const v2i::VehicleAnnouncement& a, TimeNs sweep_time,
                                       const perception::LidarGeometry& lidar) const;
  // Whether the fitted rectangle passes the vehicle's association gate at `sweep_time`.
  bool fits_vehicle(const perception::RectangleFit& fit, const v2i::VehicleAnnouncement& a,
                    TimeNs sweep_time) const;

  perception::VehicleFixConfig fix_config_;
  tracking::HypothesisConfig hypothesis_;
  tracking::AssociationConfig association_;
  perception::LidarGeometry lidar_;
  Eigen::Vector2d lidar_xy_;
  double coverage_radius_m_;
};

}  // namespace rsu::core
