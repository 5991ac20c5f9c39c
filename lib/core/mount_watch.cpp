// SPDX-License-Identifier: Apache-2.0
// RsuCore's mount watch (issue 17; calibration/mount_monitor.h): each rotation's static scene sampled
// after the corrections are sent, checked against the reference learned with the background, and what
// the vehicles and the advertisement are told while the fixes are stopped.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/rsu_core.h"
#include "core/withheld_notices.h"

namespace rsu::core {

v2i::FixesWithheld RsuCore::fixes_withheld() const {
  // Not while a saved reference awaits its first check (mount_unverified_): no wire value says "not
  // checked yet", and it lasts a rotation or two; nothing is claimed about the mount until then.
  return !monitor_ || monitor_->serving() ? v2i::FixesWithheld::kNone : mount_withheld(monitor_->cause());
}

std::vector<std::uint8_t> RsuCore::advertisement(TimeNs now) {
  const v2i::FixesWithheld withheld = fixes_withheld();
  const bool estimated = monitor_ && withheld != v2i::FixesWithheld::kMountMismatch;
  return corrections_.advertisement(now, withheld,
                                    estimated ? monitor_->stopped_by().error_at_radius_m : 0.0);
}

void RsuCore::start_mount_monitor() {
  if (!config_.mount_monitor.enabled || background_frames_->empty())
    return;
  // Its reference (planes of the background's rotations: 40-52 ms for three 128 x 2048 rotations) is
  // built when the first rotation is to be checked, a rotation after learning ended, not on top of the
  // last learning rotation's work: together they held a dense stream's loop long enough to lose packets.
  // rsud builds it on its mount check thread (check_mount_rotations).
  monitor_due_ = true;
  missing_at_last_rotation_ = packets_.order_stats().lost + lidar_stats_.packets_too_late;
}

calibration::MountReferenceSource RsuCore::mount_reference_source() const {
  // Fixes lie about a vehicle's half height above the road, below the sensor by its height over it.
  return calibration::MountReferenceSource{background_frames_, config_.mount, config_.coverage_radius_m,
                                           config_.mount.z - config_.perception.ground.ground_z,
                                           config_.mount_monitor};
}

void RsuCore::watch_mount(std::span<const lidar::LidarPoint> points, bool whole_frame) {
  if (!monitor_ && !monitor_due_)
    return;
  // The static scene only: what the background model calls background (vehicles and passers-by would
  // pull the registration). Every 4th point is plenty (the monitor takes at most sample_points of a
  // rotation) and keeps the copies small. map_scratch_ holds `points` in the map frame.
  constexpr std::size_t kEvery = 4;
  monitor_scratch_.clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (++monitor_skip_ < kEvery)
      continue;
    monitor_skip_ = 0;
    if (background_.classify(map_scratch_[i]) == perception::PointClass::background)
      monitor_scratch_.push_back(points[i]);
  }
  if (whole_frame) {
    const TimeNs end = points.empty() ? 0 : points.back().time_ns;
    mount_rotations_pending_.push_back(lidar::LidarFrame{end, end, monitor_scratch_});
    return;
  }
  // A rotation that lacked many of its packets (a daemon too slow for its LiDAR loses them in the kernel,
  // or sheds them) is no evidence either way: its registration rests on what is left of the scene, and
  // read as motion it stopped the fixes of a still sensor (a TSan rsud on busy cores). Not checked, and
  // counted (mount.rotations_gappy). A few lost packets (network loss) leave it checked on what it has.
  const std::uint64_t missing = packets_.order_stats().lost + lidar_stats_.packets_too_late;
  const TimeNs packet_period = packets_.decoder().geometry().packet_period_ns;
  const double packets_per_rotation = packet_period > 0 ? static_cast<double>(sweep_.rotation_period_ns()) /
                                                              static_cast<double>(packet_period)
                                                        : 0.0;
  for (lidar::LidarFrame& rotation : monitor_assembler_.add(monitor_scratch_)) {
    const double lacked = static_cast<double>(missing - missing_at_last_rotation_);
    missing_at_last_rotation_ = missing;
    if (lacked > config_.mount_monitor.max_missing_fraction * packets_per_rotation) {
      ++mount_rotations_gappy_;
      continue;
    }
    mount_rotations_pending_.push_back(std::move(rotation));
  }
}

MountChecks check_mount_rotations(MountRotations taken) {
  MountChecks out;
  if (!taken.reference && taken.source)
    taken.reference = std::make_shared<const calibration::MountReference>(*taken.source);
  for (const lidar::LidarFrame& rotation : taken.rotations)
    out.drifts.push_back(taken.reference->estimate(rotation.points, Pose3{}));
  out.checked = std::move(taken);
  return out;
}

std::size_t RsuCore::check_mount_pending() {
  MountRotations taken = take_mount_rotations();
  if (!taken.reference && !taken.source)
    return 0;
  const MountChecks checks = check_mount_rotations(std::move(taken));
  record_mount_checks(checks);
  return checks.drifts.size();
}

MountRotations RsuCore::take_mount_rotations() {
  MountRotations taken;
  // Nothing to check, nothing handed out: rsud submits a job whenever a reference comes, and a reference
  // with no rotations had woken its mount thread (and posted an empty result back) on every LiDAR
  // packet: 10 % of the event loop's samples with an OS1-128 (issue 16, latency; README, "a thread woken
  // for nothing").
  if (monitor_building_ || mount_rotations_pending_.empty())
    return taken;  // while building: kept pending until the reference is back
  if (monitor_due_) {
    monitor_building_ = true;
    taken.source = mount_reference_source();
  } else if (monitor_) {
    taken.reference = monitor_->reference();
  }
  if (taken.reference || taken.source)
    taken.rotations = std::move(mount_rotations_pending_);
  mount_rotations_pending_.clear();
  return taken;
}

void RsuCore::record_mount_checks(const MountChecks& checks) {
  const MountRotations& checked = checks.checked;
  if (checked.source) {
    // The reference built from this run's background (not from one a reload has replaced since).
    if (!monitor_building_ || checked.source->frames != background_frames_ || !checked.reference)
      return;
    monitor_building_ = false;
    monitor_due_ = false;
    monitor_.emplace(checked.reference);
  }
  if (!monitor_ || checked.reference != monitor_->reference())
    return;  // checked against a reference replaced since (a reload with a new mount)
  for (std::size_t i = 0; i < checks.drifts.size() && i < checked.rotations.size(); ++i) {
    if (monitor_->record(checks.drifts[i], checked.rotations[i].end_ns))
      mount_notices_.push_back(monitor_->notice());
  }
  // Where the scene holds the LiDAR weakly one rotation within says less (single rotations of a LiDAR
  // turned 1 deg there read 0.02 m and 0.29 m by turns), as it does for a motion: the monitor's
  // suspect_rotations rule stops such fixes later, as it does in service.
  if (monitor_->rotations_within_in_a_row() > 0)
    mount_unverified_ = false;
}

}  // namespace rsu::core
