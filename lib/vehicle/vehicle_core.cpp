// SPDX-License-Identifier: Apache-2.0
#include "vehicle/vehicle_core.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/symmetric_eigen.h"
#include "fusion/covariance_floor.h"

namespace rsu::vehicle {

const char* CorrectionStep::label() const {
  if (outcome) {
    return fusion::to_string(*outcome);
  }
  if (check && !check->use()) {
    return to_string(check->verdict);
  }
  return coarse ? "coarse" : "not_fused";
}

VehicleCore::VehicleCore(const VehicleCoreConfig& config)
    : config_(config), fuser_(config.fuser), own_(config.fuser.ekf), monitor_(config.integrity) {}

NdtStep VehicleCore::on_ndt(const NdtPose& ndt) {
  ++stats_.ndt_poses;
  newest_ndt_ = newest_ndt_ ? std::max(*newest_ndt_, ndt.time) : ndt.time;
  const bool flagged = assess(ndt.quality, config_.ndt_quality) == NdtHealth::kDegraded;
  const bool degraded = flagged || (last_degraded_ndt_ && ndt.time >= *last_degraded_ndt_ &&
                                    ndt.time - *last_degraded_ndt_ <= config_.degraded_ndt_persistence);
  if (flagged) {
    last_flag_failed_match_ = match_failed(ndt.quality, config_.ndt_quality);
  }
  // The match says it failed: its pose is no 3 cm (or 0.15 m) estimate. The own estimate, the reference
  // the integrity checks hold an RSU to, always takes it so.
  Eigen::Matrix3d weakened = ndt.covariance;
  if (degraded) {
    weakened *= config_.degraded_ndt_variance_scale;
    fusion::raise_to_floor(weakened, config_.degraded_ndt_min_sigma_m, 0.0);
    ++stats_.ndt_degraded;
  }
  // The fused filter only along the match's weak axis when what degrades it is its degeneracy alone.
  const bool along_axis = degraded && config_.weaken_along_weak_axis && ndt.quality.weak_axis_rad &&
                          !last_flag_failed_match_ && !match_failed(ndt.quality, config_.ndt_quality);
  Eigen::Matrix3d weakened_for_fused = weakened;
  if (along_axis) {
    weakened_for_fused = ndt.covariance;
    fusion::weaken_along_axis(weakened_for_fused, *ndt.quality.weak_axis_rad,
                              config_.degraded_ndt_variance_scale, config_.degraded_ndt_min_sigma_m);
  }
  if (degraded && !previous_degraded_) {
    doubt_own_at(ndt.time, weakened);
    monitor_.annul_exclusions_since(ndt.time - config_.ndt_degraded_hold);
  }
  own_.add({ndt.time, fusion::MeasurementSource::kNdt, ndt.pose, weakened});
  previous_degraded_ = degraded;
  if (flagged) {
    last_degraded_ndt_ = ndt.time;
  }
  const bool weaken_in_fused =
      degraded && (!config_.weaken_degraded_ndt_only_with_rsu || rsu_admitted_near(ndt.time));
  stats_.ndt_weakened_in_fused += weaken_in_fused ? 1 : 0;
  stats_.ndt_weakened_along_axis += weaken_in_fused && along_axis ? 1 : 0;
  fuser_.add_ndt(ndt.pose, weaken_in_fused ? weakened_for_fused : ndt.covariance, ndt.time);
  if (degraded && !weaken_in_fused) {
    unweakened_degraded_[ndt.time] = weakened_for_fused;
  }
  std::erase_if(unweakened_degraded_,
                [&](const auto& entry) { return ndt.time - entry.first > config_.fuser.ekf.history_window; });
  NdtStep step;
  step.fused = fuser_.pose_at(ndt.time);
  step.announce = state_to_announce(ndt, step.fused);
  return step;
}

CorrectionStep VehicleCore::on_correction(const v2i::Correction& received) {
  CorrectionStep step;
  if (!config_.fuse_corrections) {
    return step;
  }
  v2i::Correction correction = received;
  if (fusion::raise_to_floor(correction.pose_covariance, config_.min_rsu_sigma_m,
                             config_.min_rsu_yaw_sigma_rad)) {
    ++stats_.fixes_covariance_raised;
  }
  Reanchor reanchor = Reanchor::kNever;
  const auto own = own_.estimate_at(correction.sweep_time);
  if (config_.check_integrity && own) {
    const OwnEstimate status = own_status_at(correction.sweep_time);
    const bool own_failed = status != OwnEstimate::kHealthy;
    stats_.fixes_own_failed += own_failed ? 1 : 0;
    // The fix continues the track the fused filter holds (led by this source's earlier fixes while it
    // is admitted): it did not jump.
    const auto fused = fuser_.pose_at(correction.sweep_time);
    const bool on_track = fused && fix_nis(correction, *fused, config_.fuser.ekf.reference_offset) <=
                                       config_.integrity.fix_gate_chi2;
    step.check = monitor_.check(correction, *own, status, config_.fuser.ekf.reference_offset, on_track);
    if (step.check->peers_agree_against_own) {
      peers_against_own_until_ = correction.sweep_time + config_.peer_agreement_hold;
    }
    if (step.check->excluded_now) {
      forget_excluded(correction.rsu_id, status);
    }
    if (!step.check->use()) {
      hold_back(correction, *step.check);
      return step;
    }
    last_rsu_heard_ = std::max(correction.sweep_time, newest_ndt_.value_or(correction.sweep_time));
    if (step.check->admitted_now) {
      fuse_held_back(correction.rsu_id);
    }
    reanchor = step.check->peers_agree_against_own ? Reanchor::kNow
               : own_failed                        ? Reanchor::kAfterAgreeingRun
                                                   : Reanchor::kNever;
  } else if (!own) {
    ++stats_.fixes_without_own;  // the fused filter refuses it too (not initialised)
  }
  if (step.check) {
    weaken_covered_by(correction.sweep_time);  // checked and usable: an admitted RSU is heard
  }
  if (too_coarse_to_fuse(correction)) {
    step.coarse = true;
    ++stats_.fixes_coarse_not_fused;
    return step;
  }
  const std::uint64_t reanchors = fuser_.stats().rsu_reanchors;
  step.outcome = fuser_.add_rsu(correction, reanchor);
  step.reanchored = fuser_.stats().rsu_reanchors > reanchors;
  if (*step.outcome == fusion::MeasurementOutcome::kAccepted || step.reanchored) {
    step.fused = fuser_.pose_at(correction.sweep_time);
  }
  return step;
}

void VehicleCore::weaken_covered_by(TimeNs sweep) {
  std::map<TimeNs, Eigen::Matrix3d> weakened;
  for (auto it = unweakened_degraded_.lower_bound(sweep - config_.rsu_heard_hold);
       it != unweakened_degraded_.end() && it->first - sweep <= config_.rsu_heard_hold;) {
    weakened.insert(*it);
    it = unweakened_degraded_.erase(it);
  }
  if (!weakened.empty()) {
    stats_.ndt_weakened_late += fuser_.reweigh_ndt(weakened);
  }
}

void VehicleCore::forget_excluded(std::uint64_t rsu_id, OwnEstimate status) {
  const auto source = monitor_.sources().find(rsu_id);
  const bool was_used =
      source != monitor_.sources().end() && source->second.verdicts.count(FixVerdict::kUse) +
                                                    source->second.verdicts.count(FixVerdict::kUseOwnFailed) >
                                                0;
  const auto own = own_.latest();
  // Not when two RSUs overruled the own estimate: it is no better place to start from. A degraded one is
  // (its covariance says how little it knows).
  if (was_used && own && status != OwnEstimate::kOverruled) {
    fuser_.restart_from(*own);
    ++stats_.restarts_after_exclusion;
  }
}

void VehicleCore::hold_back(const v2i::Correction& correction, const FixCheck& check) {
  if (check.excluded_now || check.verdict != FixVerdict::kProbation) {
    held_back_.erase(correction.rsu_id);
    return;
  }
  if (held_back_.size() >= monitor_.config().max_sources && held_back_.count(correction.rsu_id) == 0) {
    std::erase_if(held_back_, [&](const auto& entry) { return monitor_.sources().count(entry.first) == 0; });
  }
  auto& fixes = held_back_[correction.rsu_id];
  fixes.push_back(correction);
  while (fixes.size() > static_cast<std::size_t>(std::max(config_.integrity.admit_after_fixes, 1))) {
    fixes.pop_front();
  }
}

void VehicleCore::fuse_held_back(std::uint64_t rsu_id) {
  const auto it = held_back_.find(rsu_id);
  if (it == held_back_.end()) {
    return;
  }
  for (const v2i::Correction& fix : it->second) {
    weaken_covered_by(fix.sweep_time);
    if (too_coarse_to_fuse(fix)) {
      ++stats_.fixes_coarse_not_fused;
      continue;
    }
    fuser_.add_rsu(fix);
    ++stats_.fixes_fused_after_probation;
  }
  held_back_.erase(it);
}

bool VehicleCore::too_coarse_to_fuse(const v2i::Correction& fix) const {
  const double largest_variance = SymmetricEigen2(fix.pose_covariance.topLeftCorner<2, 2>()).eigenvalues()(1);
  return !(largest_variance <= config_.coarse_fix_sigma_m * config_.coarse_fix_sigma_m) &&
         own_status_at(fix.sweep_time) == OwnEstimate::kHealthy;
}

OwnEstimate VehicleCore::own_status_at(TimeNs t) const {
  if (peers_against_own_until_ && t <= *peers_against_own_until_) {
    return OwnEstimate::kOverruled;
  }
  if (last_degraded_ndt_ && std::llabs(t - *last_degraded_ndt_) <= config_.ndt_degraded_hold) {
    return OwnEstimate::kDegraded;
  }
  return OwnEstimate::kHealthy;
}

bool VehicleCore::rsu_admitted_near(TimeNs t) const {
  return std::any_of(monitor_.sources().begin(), monitor_.sources().end(), [&](const auto& entry) {
    const SourceRecord& s = entry.second;
    return s.state == SourceState::kAdmitted && s.fixes > 0 &&
           (std::llabs(t - s.last_time) <= config_.rsu_heard_hold ||
            (last_rsu_heard_ && std::llabs(t - *last_rsu_heard_) <= config_.rsu_heard_hold));
  });
}

void VehicleCore::doubt_own_at(TimeNs time, const Eigen::Matrix3d& covariance) {
  auto estimate = own_.estimate_at(time);
  if (!estimate) {
    return;
  }
  estimate->covariance.topLeftCorner<3, 3>() += covariance;
  const double speed_sigma = config_.degraded_speed_sigma_mps;
  estimate->covariance(fusion::kSpeed, fusion::kSpeed) += speed_sigma * speed_sigma;
  own_.initialize(*estimate);
}

VehicleState VehicleCore::state_to_announce(const NdtPose& ndt,
                                            const std::optional<fusion::StateEstimate>& fused) const {
  VehicleState state{ndt.time, ndt.pose, ndt.covariance, std::nullopt, std::nullopt};
  if (!fused) {
    return state;
  }
  state.pose = fused->pose();
  state.covariance = fused->covariance.topLeftCorner<3, 3>();
  const double speed_sigma = config_.announce_speed_sigma_mps;
  const double yaw_rate_sigma = config_.announce_yaw_rate_sigma_rps;
  if (fused->covariance(fusion::kSpeed, fusion::kSpeed) < speed_sigma * speed_sigma) {
    state.speed_mps = fused->state(fusion::kSpeed);
  }
  if (fused->covariance(fusion::kYawRate, fusion::kYawRate) < yaw_rate_sigma * yaw_rate_sigma) {
    state.yaw_rate_rps = fused->state(fusion::kYawRate);
  }
  return state;
}

}  // namespace rsu::vehicle
