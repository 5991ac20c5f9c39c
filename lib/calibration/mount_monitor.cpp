// SPDX-License-Identifier: Apache-2.0
#include "calibration/mount_monitor.h"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/angles.h"

namespace rsu::calibration {
namespace {

std::string drift_text(const MountDrift& d, double tolerance_m) {
  char text[320];
  std::snprintf(text, sizeof text,
                "moved by (%.3f, %.3f, %.3f) m, roll %.3f, pitch %.3f, yaw %.3f deg since its reference: "
                "%.3f m at the coverage radius (tolerance %.3f m; %zu points matched, rms %.3f m)",
                d.motion.x, d.motion.y, d.motion.z, rad_to_deg(d.motion.roll), rad_to_deg(d.motion.pitch),
                rad_to_deg(d.motion.yaw), d.error_at_radius_m, tolerance_m, d.matches, d.rms_m);
  if (d.rotations_averaged < 2)
    return text;
  char averaged[96];
  std::snprintf(averaged, sizeof averaged, "; its weakly held directions the mean of %d rotations",
                d.rotations_averaged);
  return text + std::string(averaged);
}

}  // namespace

MountMonitor::MountMonitor(std::shared_ptr<const MountReference> reference)
    : reference_(std::move(reference)) {}

MountMonitor::MountMonitor(const std::vector<std::vector<lidar::LidarPoint>>& reference, const Pose3& mount,
                           double coverage_radius_m, double fix_height_m, const MountMonitorConfig& config)
    : reference_(std::make_shared<const MountReference>(reference, mount, coverage_radius_m, fix_height_m,
                                                        config)) {}

bool MountMonitor::check_rotation(std::span<const lidar::LidarPoint> rotation, TimeNs time) {
  if (!config().enabled)
    return false;
  // Every rotation is registered from the reference itself, not from the last estimate: along a
  // direction the scene holds weakly (a street of flat facades) an estimate started from the last one
  // keeps whatever it had there and adds its own noise, a random walk that wandered 6 cm from a still
  // mount in a minute (a false stop); from the reference, each rotation's noise is its own.
  return record(reference_->estimate(rotation, Pose3{}), time);
}

bool MountMonitor::record(const MountDrift& drift, TimeNs time) {
  if (!config().enabled)
    return false;
  if (++stats_.rotations_checked == 1)
    first_checked_ = time;
  if (!drift.observable) {
    ++stats_.rotations_unobservable;  // too few static points to tell: nothing decided
    return false;
  }
  // The evidence over the window: the rotations that match the reference (a rewound clock starts afresh).
  if (drift.matches_reference) {
    if (!recent_.empty() && time < recent_.back().time)
      recent_.clear();
    recent_.push_back(Evidence{time, drift.motion, drift.covariance});
    while (recent_.size() > kMaxAveraged || time - recent_.front().time >= config().weak_evidence_window)
      recent_.pop_front();
  }
  last_ = drift.matches_reference ? decide(drift) : drift;
  const double tolerance = config().max_position_error_m;
  const double margin = config().significance_sigmas * last_.error_sigma_m;
  // The scene cannot verify the tolerance when 3 sigma of the error alone exceed it (header).
  const bool unverifiable = last_.matches_reference && margin > tolerance;
  // Beyond the tolerance even with the weakly held directions' mean taken significance_sigmas of its
  // sigma towards the reference: what those directions say must be significant (their rotations' spread
  // is wider than stated, and a rotation missing packets shifts them: a still OS1-128's mean of 18
  // rotations read 5.3 cm at a scaled sigma of 1.5 cm through rsud on a loaded machine). The directions
  // one rotation pins down well keep the rule: their estimate beyond the tolerance, significant or not.
  const bool beyond = !last_.matches_reference ||
                      last_.error_at_radius_m - config().significance_sigmas * last_.weak_sigma_m > tolerance;
  if (!last_.matches_reference)
    ++stats_.rotations_mismatched;
  if (beyond)
    ++stats_.rotations_beyond_tolerance;
  within_run_ = beyond ? 0 : within_run_ + 1;
  // Directions held while the window's mean gathers evidence along them (start-up) do not say yet that
  // the scene cannot verify the tolerance.
  const bool gathering = last_.weak_held && time - first_checked_ < config().weak_evidence_window;
  if (unverifiable && !gathering) {
    ++stats_.rotations_unverifiable;
    if (!warned_unverifiable_) {
      warned_unverifiable_ = true;
      char text[320];
      std::snprintf(
          text, sizeof text,
          "the scene holds the LiDAR too weakly to verify its mount to %.3f m at the coverage radius "
          "(sigma %.3f m there): fixes stop on the estimate alone, beyond the tolerance, "
          "significant or not",
          tolerance, last_.error_sigma_m);
      notice_ = text;
      if (state_ == MountState::kServing && !beyond)
        return true;
    }
  }
  // Confirmed: beyond by 3 sigma, in a scene that can verify the tolerance at all (where it cannot, its
  // sigma is not to be trusted either: a still VLP-16 between two facades had single rotations 0.4 m
  // off along the street at a stated 0.04 m).
  const bool significant = !unverifiable && last_.error_at_radius_m - margin > tolerance;
  // An estimate beyond the tolerance but not significantly: a weak direction's noise, or a real motion
  // the scene cannot confirm. Withheld once it has persisted over suspect_rotations in a row.
  suspect_run_ = beyond && !significant ? suspect_run_ + 1 : 0;
  if (state_ == MountState::kServing) {
    if (!beyond || (last_.matches_reference && !significant && suspect_run_ < config().suspect_rotations))
      return false;
    stop(significant);
    return true;
  }
  // Back within resume_fraction of the tolerance by 3 sigma. Where the scene cannot verify the tolerance
  // the fixes stay withheld until a recalibration (a new mount, a new monitor): an estimate that reads
  // calm there may be one that does not see the motion at all.
  return resume_when_calm(!unverifiable && last_.matches_reference &&
                              last_.error_at_radius_m + margin <= config().resume_fraction * tolerance,
                          time);
}

void MountMonitor::stop(bool significant) {
  state_ = MountState::kMoved;
  stopped_by_ = last_;
  calm_ = false;
  suspect_run_ = 0;
  ++stats_.stops;
  if (!last_.matches_reference) {
    cause_ = StopCause::kMismatch;
    reason_ = "the LiDAR's view no longer matches its reference (" + std::to_string(last_.matches) + " of " +
              std::to_string(last_.sampled) + " static points matched): moved far";
  } else if (significant) {
    cause_ = StopCause::kMoved;
    reason_ = "the LiDAR " + drift_text(last_, config().max_position_error_m);
  } else {
    cause_ = StopCause::kSuspected;
    ++stats_.stops_unconfirmed;
    char sigma[96];
    std::snprintf(sigma, sizeof sigma, " [not confirmed: sigma %.3f m at the radius]", last_.error_sigma_m);
    reason_ = "the LiDAR may have " + drift_text(last_, config().max_position_error_m) + sigma;
  }
  notice_ = "fixes stopped: " + reason_ + ". Recalibrate (rsu-calibrate) and give rsud the new mount";
}

bool MountMonitor::resume_when_calm(bool calm, TimeNs time) {
  if (!calm) {
    calm_ = false;
    return false;
  }
  if (!calm_) {
    calm_ = true;
    calm_since_ = time;
  }
  if (time - calm_since_ < config().resume_after)
    return false;
  state_ = MountState::kServing;
  cause_ = StopCause::kNone;
  ++stats_.resumes;
  notice_ = "fixes resumed: the LiDAR is back within tolerance (" +
            drift_text(last_, config().max_position_error_m) + ")";
  reason_.clear();
  return true;
}

}  // namespace rsu::calibration
