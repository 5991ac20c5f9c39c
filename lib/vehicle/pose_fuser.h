// SPDX-License-Identifier: Apache-2.0
// The vehicle's pose fuser: lib/fusion's CTRV EKF (x, y, yaw, speed, yaw rate) fed with the vehicle's
// NDT poses and the RSU corrections it receives, each at its own time with its own covariance. An RSU
// correction counts at its sweep time (when the LiDAR swept the vehicle), its box yaw is used modulo pi, one
// arriving after newer NDT poses is inserted and the later ones re-applied, and an outlier (an off-by-90 deg
// box, a wrong cluster) is refused by the Mahalanobis gate so it never moves the pose (issue 4, item 3).
#pragma once

#include <cstdint>
#include <map>
#include <optional>

#include "common/pose.h"
#include "common/time.h"
#include "fusion/vehicle_ekf.h"
#include "v2i/messages.h"

namespace rsu::vehicle {

struct PoseFuserConfig {
  // reference_offset must equal the one announced to the RSU (corrections give the box centre).
  fusion::VehicleEkfConfig ekf;
  // Re-anchoring. The gate protects the pose from a bad RSU fix, but it also locks out good fixes once
  // the filter itself has drifted (NDT in a featureless street claims 0.15 m while it is metres off).
  // Only the caller knows whether the filter is the one that failed (the vehicle's own NDT says it is
  // degraded, or two RSUs agree against it: VehicleCore), and says so with each fix (Reanchor). With
  // kAfterAgreeingRun, `reanchor_after` gate-refused fixes in a row that agree with each other (each
  // within `reanchor_agreement_m` of the previous one carried forward with the filter's own speed and
  // yaw) re-initialise the filter at the latest; an off-by-90 deg box fails the yaw-branch test instead
  // and never counts. One RSU's consistency with itself is never reason enough.
  int reanchor_after = 3;
  double reanchor_agreement_m = 0.3;
  TimeNs reanchor_max_gap = 500'000'000;  // fixes farther apart do not form a run
};

// May a gate-refused RSU fix re-initialise the filter?
enum class Reanchor : std::uint8_t {
  kNever,             // the filter is not known to have failed
  kAfterAgreeingRun,  // it has (its NDT is degraded): after a run of agreeing refused fixes
  kNow,               // it has, and independent RSUs agree on where the vehicle is: at this fix
};

// Decisions at arrival, per source. A late measurement can change the decision about later ones when
// they are re-applied; the EKF's own counts (ekf_stats()) follow those changes.
struct PoseFuserStats {
  std::uint64_t ndt_accepted = 0;  // including the pose that started the filter
  std::uint64_t ndt_rejected = 0;
  std::uint64_t rsu_accepted = 0;
  std::uint64_t rsu_rejected_gate = 0;        // chi-square gate on the innovation
  std::uint64_t rsu_rejected_yaw_branch = 0;  // box yaw about 90 deg off: the L-shape failure
  std::uint64_t rsu_rejected_other = 0;       // too old, before any NDT pose, invalid
  std::uint64_t late = 0;                     // arrived older than the newest fused measurement
  std::uint64_t reapplied = 0;                // later measurement updates redone because of a late one
  std::uint64_t rsu_reanchors = 0;            // filter re-initialised at RSU fixes (Reanchor)
  std::uint64_t ndt_restarts = 0;  // filter restarted at an NDT pose after a lock-out (VehicleEkfConfig)

  std::uint64_t rsu_rejected_by_gate() const { return rsu_rejected_gate + rsu_rejected_yaw_branch; }
};

class PoseFuser {
 public:
  explicit PoseFuser(const PoseFuserConfig& config = {});

  // The vehicle's own NDT pose of its reference point (full heading) at `time`.
  fusion::MeasurementOutcome add_ndt(const Pose2& pose, const Eigen::Matrix3d& covariance, TimeNs time);
  // An RSU correction: box centre and box yaw (mod pi) at the correction's sweep time. A fix the gate
  // refuses re-initialises the filter only as `reanchor` allows.
  fusion::MeasurementOutcome add_rsu(const v2i::Correction& correction, Reanchor reanchor = Reanchor::kNever);

  // NDT poses already fused given other covariances (fusion::VehicleEkf::reweigh_ndt).
  std::size_t reweigh_ndt(const std::map<TimeNs, Eigen::Matrix3d>& covariances) {
    return ekf_.reweigh_ndt(covariances);
  }

  // The fused estimate at `time` (predicted from the nearest earlier state). Empty before the first NDT
  // pose.
  std::optional<fusion::StateEstimate> pose_at(TimeNs time) const;
  std::optional<fusion::StateEstimate> latest() const { return ekf_.latest(); }

  // Starts again from `estimate`, dropping the history: after an RSU was found faulty, its fixes already
  // fused must not linger in the pose (VehicleCore restarts from the vehicle's own estimate).
  void restart_from(const fusion::StateEstimate& estimate) { ekf_.initialize(estimate); }

  PoseFuserStats stats() const;
  const fusion::EkfStats& ekf_stats() const { return ekf_.stats(); }

 private:
  // True when `correction` completes a run of agreeing, gate-rejected fixes.
  bool completes_agreeing_run(const v2i::Correction& correction);
  // Re-initialises the filter at the fix: its box centre back to the reference point, its box yaw on the
  // branch nearest the filter's heading, speed and yaw rate kept.
  void reanchor_at(const v2i::Correction& correction);

  PoseFuserConfig config_;
  fusion::VehicleEkf ekf_;
  PoseFuserStats stats_;
  std::optional<v2i::Correction> last_rejected_;
  int rejected_run_ = 0;
};

}  // namespace rsu::vehicle
