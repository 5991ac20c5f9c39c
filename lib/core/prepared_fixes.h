// SPDX-License-Identifier: Apache-2.0
// Fits and fixes computed ahead of a cluster's release (issue 16, latency). The sweep clusterer releases
// a cluster only once no later point can join it (sweep_clusterer.h), and that rule is exact: near the
// LiDAR it waits 10-15 deg of sweep past the vehicle (a VLP-32C's car at 5 m: 3.3-4.0 ms after its last
// packet, whose -4.2 deg lasers pass over the roof and could still return a tall neighbour's point
// within the tolerance). Once every laser has swept past a cluster nothing else can change it, so
// RsuCore fits and fixes it meanwhile (RsuCore::prepare_fixes, in prepared_fixes.cpp) and keeps the
// results here with their exact inputs. The release takes them only when its inputs are the same bit for
// bit (points, announcement, ...) and its occluders answer every question the fix asked of them alike,
// else computes them: the corrections are the same either way, only ready sooner
// (RsuCoreConfig::prepare_fixes turns it off, the baseline). The occluders need not be the same: a car
// parked behind a passing one is held until the sweep has passed its footprint, and the passing car's
// points near it go on arriving until then (the load test's OS1-128 run, 45 s: fixes used at their
// release 1,621-1,666 of 1,905 prepared while the occluders had to be the same, 1,697-1,710 since).
//
// The preparation itself is pure (prepare(), below): RsuCore hands out what to prepare
// (RsuCore::take_preparation) and takes the results back (RsuCore::record_prepared), so that rsud runs it
// on a thread of its own. A result that comes back too late is merely unused.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/time.h"
#include "core/gathered_fix.h"
#include "core/lidar_stats.h"
#include "core/vehicle_gatherer.h"
#include "lidar/point.h"
#include "perception/detection.h"
#include "perception/lidar_geometry.h"
#include "perception/size_correction.h"
#include "perception/sweep_clusterer.h"
#include "v2i/messages.h"

namespace rsu::core {

// GatheredVehicleFixer::fix's inputs: what a vehicle's prepared fix is keyed by.
struct FixInputs {
  HeldVehicle held;
  v2i::VehicleAnnouncement announcement;
  bool lost_nearby = false;
  std::vector<Eigen::Vector2d> occluders;
};

// What to prepare: the clusters every laser has swept past (to fit) and the held vehicles (to fix), with
// the fixer they are prepared by. The fixer is immutable and shared: a reload makes a new one, and what an
// old one prepared is dropped (RsuCore::record_prepared).
struct Preparation {
  std::shared_ptr<const GatheredVehicleFixer> fixer;
  TimeNs step_time = 0;  // the step that left the clusters: their vehicles are predicted to its time
  std::vector<std::vector<lidar::LidarPoint>> clusters;
  std::vector<FixInputs> vehicles;

  bool empty() const { return clusters.empty() && vehicles.empty(); }
};

// A fix with its inputs and what it asked of the occluders (GatheredVehicleFixer::answers_alike).
struct PreparedFix {
  FixInputs inputs;
  GatheredFix fix;
  std::vector<perception::OcclusionQuery> occlusion_queries;
};

// Their fits and fixes, each with its inputs.
struct Prepared {
  std::shared_ptr<const GatheredVehicleFixer> fixer;
  TimeNs step_time = 0;
  std::vector<std::pair<std::vector<lidar::LidarPoint>, perception::Detection>> fits;
  std::vector<PreparedFix> fixes;
};

// Fits and fixes what `preparation` holds. Pure, and touching nothing of the core: rsud runs it on a
// thread of its own.
Prepared prepare(Preparation preparation);

// Released open (RsuCoreConfig::release_fixed_open). A cluster every laser has swept past is complete
// unless a later return comes within the clustering tolerance, and near the LiDAR the sweep needs another
// asin(d / r) to rule that out: 8-10 deg, 2.2-2.8 ms at 10 Hz, for a car passing 4-5 m from the mast. Such
// a return is the vehicle's only if the vehicle reaches beyond what the sweep has passed. Once its fix is
// prepared, the fix's box grown by 3 sigma bounds where the vehicle is; when every laser has swept past
// that too, no return of the vehicle can still come, and the cluster is released open: what would still
// join it is another object's (a pedestrian beside the car, a pole), which the closed cluster would have
// mixed into the fix, and it forms a cluster of its own instead. The cluster and the box it waits for:
struct FixedOpenCluster {
  perception::OpenClusterName name;
  std::array<Eigen::Vector2d, 4> outline;  // map frame
};
// The corners of `fix`'s box (the announced `length_m` x `width_m` at its pose) grown on every side by 3
// sigma of a corner's displacement: its position's sigma (the larger axis) and its yaw's turning the
// corners, independent.
std::array<Eigen::Vector2d, 4> grown_box_outline(const perception::CorrectedPose& fix, double length_m,
                                                 double width_m);

class PreparedFixes {
 public:
  // A cluster's fit, by its points.
  void add_fit(std::vector<lidar::LidarPoint>&& points, perception::Detection detection);
  // A released cluster's fit: the one prepared for exactly these points (then forgotten), else computed
  // by `fixer`.
  perception::Detection fit(std::span<const lidar::LidarPoint> points, const GatheredVehicleFixer& fixer);
  // A vehicle's fix, by GatheredVehicleFixer::fix's inputs.
  void add(PreparedFix&& fix);
  // A released vehicle's fix: the one prepared for these inputs, its occluders answering alike (then
  // forgotten; counted as fixes_prepared_used), else computed by `fixer`.
  GatheredFix fix(const GatheredVehicleFixer& fixer, const HeldVehicle& held,
                  const v2i::VehicleAnnouncement& a, bool lost_nearby,
                  const std::vector<Eigen::Vector2d>& occluders, LidarStats& stats);

 private:
  static constexpr std::size_t kKept = 8;  // the newest of each; one is taken within a few packets
  std::vector<std::pair<std::vector<lidar::LidarPoint>, perception::Detection>> fits_;
  std::vector<PreparedFix> fixes_;
};

}  // namespace rsu::core
