// SPDX-License-Identifier: Apache-2.0
// Mount integrity (issue 17): is the LiDAR still where its mount says? Each rotation's static scene is
// registered against the reference the mount belongs to (mount_reference.h); the result is the sensor's
// motion since (a bump, a leaning pole), and what it does to a fix: the largest horizontal displacement
// it causes at the coverage radius. Beyond a tolerance the fixes stop; they
// resume once the motion has stayed back within it (hysteresis) for a while, or when a new mount and
// reference replace this monitor (a recalibration).
//
// Pure: the caller gives it rotations (sensor frame) and their time; no clock, no files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "calibration/mount_reference.h"
#include "common/pose.h"
#include "common/time.h"
#include "lidar/point.h"

namespace rsu::calibration {

enum class MountState { kServing, kMoved };

// Why the fixes are stopped: the motion confirmed beyond the tolerance (by significance_sigmas), the
// estimate beyond it in a scene too weak to confirm it (a suspected motion: withheld all the same, since
// a bumped sensor must never mislead a vehicle), or a view that no longer matches the reference.
enum class StopCause { kNone, kMoved, kSuspected, kMismatch };

struct MountMonitorStats {
  std::uint64_t rotations_checked = 0;
  std::uint64_t rotations_beyond_tolerance = 0;
  std::uint64_t rotations_unobservable = 0;  // too few static points to tell (nothing decided)
  std::uint64_t rotations_mismatched = 0;    // enough, but too few on the reference's planes
  // the estimate too uncertain to tell (3 sigma of the error beyond the tolerance): the scene holds the
  // sensor too weakly in some direction (a street of flat walls along it)
  std::uint64_t rotations_unverifiable = 0;
  std::uint64_t stops = 0;              // serving -> moved
  std::uint64_t stops_unconfirmed = 0;  // of them on the estimate alone (StopCause::kSuspected)
  std::uint64_t resumes = 0;            // moved -> serving
};

class MountMonitor {
 public:
  explicit MountMonitor(std::shared_ptr<const MountReference> reference);
  // Builds its reference (MountReference's constructor: the same arguments).
  MountMonitor(const std::vector<std::vector<lidar::LidarPoint>>& reference, const Pose3& mount,
               double coverage_radius_m, double fix_height_m, const MountMonitorConfig& config);

  // One rotation (sensor frame), swept by `time`: registered and recorded. Returns true when the state
  // changed (notice()).
  bool check_rotation(std::span<const lidar::LidarPoint> rotation, TimeNs time);
  // The same for a rotation registered elsewhere (reference().estimate(rotation, Pose3{}) on another
  // thread), recorded in the order the rotations were swept.
  bool record(const MountDrift& drift, TimeNs time);

  // Shared with whoever registers rotations for record() (immutable).
  const std::shared_ptr<const MountReference>& reference() const { return reference_; }
  MountState state() const { return state_; }
  bool serving() const { return state_ == MountState::kServing; }
  const MountDrift& last() const { return last_; }
  const MountMonitorStats& stats() const { return stats_; }
  // Observable rotations in a row, up to the last, within the tolerance (not beyond it; unobservable
  // ones neither break nor extend the run).
  int rotations_within_in_a_row() const { return within_run_; }
  std::size_t reference_planes() const { return reference_->planes(); }
  // Why the fixes stopped or resumed, for the log (set when check_rotation() returns true).
  const std::string& notice() const { return notice_; }
  // Why the fixes are stopped now (empty while serving): for the advertisement and the stats.
  const std::string& reason() const { return reason_; }
  StopCause cause() const { return cause_; }
  // The estimate that stopped the fixes (while stopped: the advertisement's and the log's reason).
  const MountDrift& stopped_by() const { return stopped_by_; }

 private:
  static constexpr std::size_t kMaxAveraged = 64;  // rotations kept over weak_evidence_window, at most
  // A rotation's estimate, kept over weak_evidence_window.
  struct Evidence {
    TimeNs time = 0;
    Pose3 motion;
    Matrix6d covariance = Matrix6d::Zero();  // of (dt, w)
  };
  const MountMonitorConfig& config() const { return reference_->config(); }
  // What the monitor decides on, from the newest rotation (the last of recent_): its own estimate along
  // the directions it pins down well, the window's mean along those it pins down only weakly
  // (mount_monitor_decide.cpp).
  MountDrift decide(const MountDrift& newest) const;
  // Serving -> moved, with the cause and reason of the last estimate (significant: confirmed).
  void stop(bool significant);
  // Moved -> serving once `calm` has held for resume_after; true when it resumed.
  bool resume_when_calm(bool calm, TimeNs time);

  std::shared_ptr<const MountReference> reference_;
  MountState state_ = MountState::kServing;
  StopCause cause_ = StopCause::kNone;
  TimeNs calm_since_ = 0;  // the first of the rotations in a row within resume_fraction (while moved)
  bool calm_ = false;
  int suspect_run_ = 0;          // rotations in a row with a suspected motion
  int within_run_ = 0;           // rotations in a row within the tolerance
  std::deque<Evidence> recent_;  // the rotations matching the reference over weak_evidence_window
  TimeNs first_checked_ = 0;     // the first rotation's time
  MountDrift last_;
  MountDrift stopped_by_;
  MountMonitorStats stats_;
  std::string notice_;
  std::string reason_;
  bool warned_unverifiable_ = false;
};

}  // namespace rsu::calibration
