// SPDX-License-Identifier: Apache-2.0
#include "core/withheld_notices.h"

#include <cmath>

namespace rsu::core {
namespace {

// The wire's reason for a fix that is not sent (nothing when it is).
std::optional<v2i::FixWithheldReason> reason_of(const GatheredFix& fix, v2i::FixesWithheld mount) {
  using Reason = v2i::FixWithheldReason;
  switch (fix.outcome) {
    case GatheredFixOutcome::fixed:
      return mount == v2i::FixesWithheld::kNone ? std::nullopt : std::optional(Reason::kMount);
    case GatheredFixOutcome::doubtful_cluster:
    case GatheredFixOutcome::no_assigned_cluster:
      return Reason::kNoOwnCluster;
    case GatheredFixOutcome::fit_failed:
      return Reason::kNoFit;
    case GatheredFixOutcome::out_of_coverage:
      return Reason::kOutOfCoverage;
    case GatheredFixOutcome::inconsistent:
    case GatheredFixOutcome::track_conflict:
      return Reason::kInconsistent;
    case GatheredFixOutcome::correction_failed:
      break;
  }
  switch (fix.fix.status()) {
    case perception::CorrectionStatus::position_unbounded:
      return Reason::kPositionUnbounded;
    case perception::CorrectionStatus::yaw_unobserved:
      return Reason::kYawUnobserved;
    case perception::CorrectionStatus::inconsistent_box:
      return Reason::kInconsistent;
    case perception::CorrectionStatus::ok:
    case perception::CorrectionStatus::no_fit:
    case perception::CorrectionStatus::invalid_size:
    case perception::CorrectionStatus::invalid_input:
      break;
  }
  // An invalid size or prior: rsud's announcement validation and the fixer keep those out.
  return Reason::kNoFit;
}

}  // namespace

v2i::FixesWithheld mount_withheld(calibration::StopCause cause) {
  switch (cause) {
    case calibration::StopCause::kSuspected:
      return v2i::FixesWithheld::kMountSuspected;
    case calibration::StopCause::kMismatch:
      return v2i::FixesWithheld::kMountMismatch;
    case calibration::StopCause::kMoved:
    case calibration::StopCause::kNone:
      break;
  }
  return v2i::FixesWithheld::kMountMoved;
}

std::optional<v2i::FixWithheld> withheld_notice(const GatheredFix& fix, const v2i::VehicleAnnouncement& a,
                                                std::uint64_t rsu_id, bool lost_nearby,
                                                v2i::FixesWithheld mount,
                                                const perception::CorrectionConfig& correction) {
  const std::optional<v2i::FixWithheldReason> reason = reason_of(fix, mount);
  if (!reason)
    return std::nullopt;
  v2i::FixWithheld n;
  n.rsu_id = rsu_id;
  n.vehicle_id = a.vehicle_id;
  n.announcement_sequence = a.sequence;
  n.sweep_time = fix.sweep_time;
  n.reason = *reason;
  n.packets_lost_nearby = lost_nearby;
  if (*reason == v2i::FixWithheldReason::kMount)
    n.mount_cause = mount;
  // How far from a fix it was: the sigma the fix would have stated, against the most one may state.
  const double sigma = perception::position_sigma_m(fix.fix.corrected);
  if (*reason == v2i::FixWithheldReason::kPositionUnbounded && std::isfinite(sigma)) {
    n.position_sigma_m = sigma;
    n.max_position_sigma_m = perception::max_position_sigma_m(!lost_nearby, correction);
  }
  return n;
}

std::optional<v2i::FixWithheld> WithheldNotices::consider(v2i::FixWithheld notice, TimeNs now) {
  if (!limits_.admit(notice.vehicle_id, now)) {
    rate_limited_.add(notice.reason);
    return std::nullopt;
  }
  notices_.add(notice.reason);
  return notice;
}

WithheldNotices WithheldNotices::reloaded(const NoticeConfig& next) const {
  WithheldNotices fresh(next);
  fresh.notices_ = notices_;
  fresh.rate_limited_ = rate_limited_;
  return fresh;
}

void WithheldNotices::report(CounterList& out) const {
  out.add_all("withheld_notice", notices_, v2i::FixWithheldReason::kPositionUnbounded);
  out.add_all("withheld_notice.rate_limited", rate_limited_, v2i::FixWithheldReason::kPositionUnbounded);
}

}  // namespace rsu::core
