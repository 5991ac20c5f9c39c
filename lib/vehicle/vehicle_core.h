// SPDX-License-Identifier: Apache-2.0
// The vehicle's side of RSU-assisted localization as one pure loop (no sockets, threads or clocks; the
// caller passes the data in with their times): its own NDT poses and the RSU corrections it accepted
// (CorrectionFilter) are fused (PoseFuser over lib/fusion's EKF), and each NDT pose yields the state to
// announce next (Announcer sends it). rsu-vehicle and the rsu_vehicle_client library are I/O around it.
//
// An RSU is never let to make the vehicle worse (issue 18): beside the fused filter runs the vehicle's
// own estimate, a filter over its NDT poses alone, and every correction is checked against it by the
// IntegrityMonitor before it may be fused. The own estimate counts as failed only when the vehicle's
// NDT says so (NdtQuality: the pose's covariance is then inflated in the own estimate, and in the fused
// filter while an admitted RSU can take over; RSU fixes may re-anchor the fused filter) or when two RSUs
// agree against it; never because one RSU keeps disagreeing. The checks are only as sharp as the NDT
// covariance is honest: a fixed 0.15 m hides an RSU 0.1-0.25 m off (README, issue 18).
#pragma once

#include <Eigen/Core>
#include <deque>
#include <map>
#include <optional>

#include "common/pose.h"
#include "common/time.h"
#include "fusion/vehicle_ekf.h"
#include "v2i/messages.h"
#include "vehicle/announcer.h"
#include "vehicle/integrity_monitor.h"
#include "vehicle/ndt_quality.h"
#include "vehicle/pose_fuser.h"

namespace rsu::vehicle {

// One pose of the vehicle's own NDT scan matching: its reference point, full heading, covariance.
struct NdtPose {
  TimeNs time = 0;
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // (x, y, yaw)
  NdtQuality quality;                                        // how the match went, when the localization says
};

struct VehicleCoreConfig {
  PoseFuserConfig fuser;
  // False: corrections are recorded but not fused, so the output is the NDT-only filter (a baseline).
  bool fuse_corrections = true;
  // False: every correction goes to the fused filter unchecked (its gate only): for comparison only.
  bool check_integrity = true;
  IntegrityConfig integrity;
  NdtQualityLimits ndt_quality;
  // A degraded NDT pose's covariance is multiplied by this, and its position raised to at least
  // `degraded_ndt_min_sigma_m`: a match that says it failed is no 3 cm (or 0.15 m) estimate, whatever
  // its curvature claims (the degraded corridor's NDT was up to 0.46 m off along the road while its
  // Laplace covariance said 3-6 cm). Less lets the degraded NDT pull the pose from a good RSU (0.3 m:
  // the VLP-16's fused MAE there 0.102 m, 0.45 m: 0.054 m; replayed, README).
  double degraded_ndt_variance_scale = 4.0;
  double degraded_ndt_min_sigma_m = 0.45;
  // A pose degraded by its degeneracy alone (the match converged and fits the map, but holds the vehicle
  // weakly along one direction: NdtQuality::weak_axis_rad) is weakened so along that direction only;
  // across it and in yaw it keeps its covariance. Weakened in every direction, the fused filter threw
  // away what NDT knows across the road and in yaw, and between a sweep and its late correction carried
  // the pose on its own motion model alone: through the degraded corridor's lane change it lagged
  // 5-8 cm across the road with corrections 200 ms late (replayed, README "The V2I link impaired").
  // The own estimate, the reference the integrity checks hold an RSU to, still takes such a pose as
  // weakened in every direction: held to NDT's claims across the road and in yaw, an honest RSU was
  // excluded in two of six noise seeds of the degraded corridor.
  bool weaken_along_weak_axis = true;
  // The own estimate (the integrity reference) always takes a degraded pose so. The fused filter only
  // while an RSU is admitted and was heard within ndt_degraded_hold: with no outside source to take over,
  // the NDT pose is the best the vehicle has, and weakening it only makes the filter lag NDT's own wander
  // (the degraded corridor with no RSU: 0.156 m against NDT's 0.135 m).
  bool weaken_degraded_ndt_only_with_rsu = true;
  // "Heard": a fix of an admitted RSU arrived (the vehicle's newest NDT time then) or was swept within
  // this of the NDT pose. Counted from the arrival too, so that a late link does not shorten it (with
  // fixes 500 ms late, a pose 0.5 s after the last arrival was already 1 s after its sweep); 1.5 s
  // bridges 14 fixes lost in a row at 10 Hz. When a fix comes after a longer gap, the degraded poses
  // within this of its sweep that counted unweakened are weakened after all (the filter redone from the
  // first), so that the returning fixes are not held to the degraded NDT's drift. Measured (README "The
  // V2I link impaired"): 500 ms late, half the fixes lost and 13 in a row, the fused maximum above NDT's
  // in 25 of 130 replayed cases with 1 s, 12 with 1.5 s, 10 with 2 s; the VLP-16's frames beyond its last
  // fix (36-50 m, coasting) 0-9 mm worse with 1.5 s than with 1 s, 40-60 % below NDT there (six noise
  // seeds; not in the one where the RSU had been falsely excluded).
  TimeNs rsu_heard_hold = 1500 * kNsPerMs;
  // A healthy-looking pose this soon after a degraded one is taken as degraded too: the street that made
  // the match fail is still there (the degraded corridor's poses between flagged ones were as far off).
  // 0.5 s: in the corridor only two poses are flagged, and a longer persistence blinds the checks after
  // them (the 0.5 deg mount-yaw RSU fused to 0.034 m with 1 s, 0.024 m with 0.5 s; replayed).
  TimeNs degraded_ndt_persistence = 500 * kNsPerMs;
  // ... and the own estimate counts as failed from this long before to this long after it.
  TimeNs ndt_degraded_hold = 1 * kNsPerSecond;
  // The own estimate's speed may have followed the failing match before it said so.
  double degraded_speed_sigma_mps = 1.0;
  // No RSU fix is credited with less than this (its covariance is raised to it): a roadside LiDAR's
  // range alone is good to a few cm (the VLP-16's and VLP-32C's +-3 cm), and its box fit to no better
  // than that, so an RSU claiming 7 mm is overconfident, and an overconfident fix would lock the fused
  // filter onto its errors.
  double min_rsu_sigma_m = 0.03;
  double min_rsu_yaw_sigma_rad = 0.0087;  // 0.5 deg
  // An RSU fix stating more than this (its position covariance's larger axis) is not fused while the own
  // estimate is healthy: beside a good NDT it adds little, and its error repeats from rotation to rotation
  // (an elevated RSU's view of a car's roof leaves its place along the length open by the same interval
  // each time), which the filter, fusing each fix as independent, would take for information: with rsud
  // sending fixes up to 1 m from 4 m up, the corridor's fused MAE went 0.023 -> 0.028 m (README "The cap
  // at 1 m, an operator's choice"). While the own estimate is degraded or overruled they are fused: there
  // they help. Infinite: every fix fused.
  double coarse_fix_sigma_m = 0.5;
  // Two RSUs agreeing against the own estimate: it counts as failed this long after.
  TimeNs peer_agreement_hold = 1 * kNsPerSecond;
  // The filter's motion estimate is announced once it has settled to these standard deviations (loose
  // but honest); until then speed and yaw rate are announced as unknown.
  double announce_speed_sigma_mps = 1.0;
  double announce_yaw_rate_sigma_rps = 0.2;
};

// What became of an NDT pose: the fused estimate at its time (empty before the filter started) and the
// state to announce (the fused estimate with its motion once known, else the NDT pose itself).
struct NdtStep {
  std::optional<fusion::StateEstimate> fused;
  VehicleState announce;
};

// What became of a correction: refused by the integrity check (`check` says why), or given to the fused
// filter (`outcome`; `fused`: the estimate at its sweep time, when it was accepted).
struct CorrectionStep {
  std::optional<FixCheck> check;                      // empty when not checked
  std::optional<fusion::MeasurementOutcome> outcome;  // empty when not given to the fused filter
  std::optional<fusion::StateEstimate> fused;
  bool reanchored = false;  // the fused filter was re-initialised at this fix
  bool coarse = false;      // usable, but coarser than the own estimate needs (coarse_fix_sigma_m)
  // "accepted", "rejected_gate", ... (the fused filter's outcome); "probation", "excluded", "barred",
  // "inconsistent" (refused by the integrity check); "coarse" (not fused: coarse_fix_sigma_m);
  // "not_fused" (corrections not fused at all).
  const char* label() const;
};

struct VehicleCoreStats {
  std::uint64_t ndt_poses = 0;
  std::uint64_t ndt_degraded = 0;             // poses whose quality said the match failed (or just had)
  std::uint64_t ndt_weakened_in_fused = 0;    // ... of them weakened in the fused filter (an RSU admitted)
  std::uint64_t ndt_weakened_along_axis = 0;  // ... of them weakened along their weak axis only
  std::uint64_t fixes_own_failed = 0;         // fixes checked while the own estimate counted as failed
  std::uint64_t fixes_without_own = 0;        // fixes before the own estimate existed
  std::uint64_t fixes_fused_after_probation = 0;  // held back on probation, fused once admitted
  std::uint64_t restarts_after_exclusion = 0;     // fused filter restarted from the own estimate
  std::uint64_t fixes_covariance_raised = 0;      // fixes claiming less than min_rsu_sigma_*
  std::uint64_t fixes_coarse_not_fused = 0;       // usable fixes over coarse_fix_sigma_m, own healthy
  std::uint64_t ndt_weakened_late = 0;  // degraded poses fused unweakened, weakened when a late fix came
};

class VehicleCore {
 public:
  explicit VehicleCore(const VehicleCoreConfig& config = {});

  NdtStep on_ndt(const NdtPose& ndt);
  CorrectionStep on_correction(const v2i::Correction& correction);

  std::optional<fusion::StateEstimate> pose_at(TimeNs time) const { return fuser_.pose_at(time); }
  // The own estimate (NDT poses alone), the integrity reference.
  std::optional<fusion::StateEstimate> own_pose_at(TimeNs time) const { return own_.estimate_at(time); }
  PoseFuserStats fuser_stats() const { return fuser_.stats(); }
  const IntegrityMonitor& integrity() const { return monitor_; }
  const VehicleCoreStats& stats() const { return stats_; }

 private:
  VehicleState state_to_announce(const NdtPose& ndt, const std::optional<fusion::StateEstimate>& fused) const;
  OwnEstimate own_status_at(TimeNs t) const;
  // A usable fix the fused filter is not given: coarser than coarse_fix_sigma_m while the own estimate is
  // healthy at its sweep time.
  bool too_coarse_to_fuse(const v2i::Correction& fix) const;
  // An admitted RSU was heard within ndt_degraded_hold of `t`: someone can take over from a failed NDT.
  bool rsu_admitted_near(TimeNs t) const;
  // The first degraded NDT pose after healthy ones: the match may have been failing before it said so,
  // so the own estimate's pose uncertainty grows by the degraded pose's covariance and its speed
  // uncertainty by degraded_speed_sigma_mps (the degraded poses themselves then come in with theirs).
  void doubt_own_at(TimeNs time, const Eigen::Matrix3d& covariance);
  // A source on probation moves nothing, but its latest fixes (which its admission will have shown
  // consistent) are kept and fused, late, the moment it is admitted.
  void hold_back(const v2i::Correction& correction, const FixCheck& check);
  // An RSU that was fused has just been excluded: like a RAIM receiver dropping a faulty satellite, the
  // fused filter falls back to the solution without it, the own estimate (other RSUs re-converge it).
  void forget_excluded(std::uint64_t rsu_id, OwnEstimate status);
  void fuse_held_back(std::uint64_t rsu_id);
  // An admitted RSU's fix swept at `sweep` is about to be fused, after degraded NDT poses that came when no
  // RSU was heard and so counted at their own covariance: those within rsu_heard_hold of the sweep (before
  // or after it, as rsu_admitted_near judges) are given the weakened one they would have had, had the fix
  // come in time (lost fixes and a late link otherwise leave the filter on the degraded NDT's drift, speed
  // included, and the returning fixes outside its gate).
  void weaken_covered_by(TimeNs sweep);

  VehicleCoreConfig config_;
  PoseFuser fuser_;
  fusion::VehicleEkf own_;
  IntegrityMonitor monitor_;
  VehicleCoreStats stats_;
  std::optional<TimeNs> last_degraded_ndt_;
  std::optional<TimeNs> newest_ndt_;      // the newest NDT pose's time: the vehicle's clock
  std::optional<TimeNs> last_rsu_heard_;  // when a fix of an admitted RSU last arrived (rsu_heard_hold)
  // Degraded NDT poses the fused filter took at their own covariance (no RSU heard), kept for the
  // fused filter's history window: their time and the weakened covariance (weaken_covered_by).
  std::map<TimeNs, Eigen::Matrix3d> unweakened_degraded_;
  bool last_flag_failed_match_ = false;  // the last flagged pose's match failed (not only degenerate)
  bool previous_degraded_ = false;
  std::optional<TimeNs> peers_against_own_until_;
  std::map<std::uint64_t, std::deque<v2i::Correction>> held_back_;  // per RSU on probation
};

}  // namespace rsu::vehicle
