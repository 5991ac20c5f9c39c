// SPDX-License-Identifier: Apache-2.0
#include "vehicle/pose_fuser.h"

#include <cmath>

#include "common/angles.h"

namespace rsu::vehicle {

using fusion::MeasurementOutcome;

namespace {

double heading_of(const fusion::StateEstimate& e) {
  return e.state(fusion::kYaw);
}

bool is_accepted(MeasurementOutcome outcome) {
  return outcome == MeasurementOutcome::kAccepted || outcome == MeasurementOutcome::kInitialized;
}

}  // namespace

PoseFuser::PoseFuser(const PoseFuserConfig& config) : config_(config), ekf_(config.ekf) {}

MeasurementOutcome PoseFuser::add_ndt(const Pose2& pose, const Eigen::Matrix3d& covariance, TimeNs time) {
  const MeasurementOutcome outcome = ekf_.add({time, fusion::MeasurementSource::kNdt, pose, covariance});
  is_accepted(outcome) ? ++stats_.ndt_accepted : ++stats_.ndt_rejected;
  return outcome;
}

MeasurementOutcome PoseFuser::add_rsu(const v2i::Correction& correction, Reanchor reanchor) {
  const MeasurementOutcome outcome = ekf_.add(
      {correction.sweep_time, fusion::MeasurementSource::kRsu, correction.pose, correction.pose_covariance});
  switch (outcome) {
    case MeasurementOutcome::kAccepted:
    case MeasurementOutcome::kInitialized:
      ++stats_.rsu_accepted;
      rejected_run_ = 0;
      last_rejected_.reset();
      break;
    case MeasurementOutcome::kRejectedGate:
      ++stats_.rsu_rejected_gate;
      if (reanchor == Reanchor::kNow ||
          (reanchor == Reanchor::kAfterAgreeingRun && completes_agreeing_run(correction))) {
        reanchor_at(correction);
      } else if (reanchor == Reanchor::kNever) {
        rejected_run_ = 0;
        last_rejected_.reset();
      }
      break;
    case MeasurementOutcome::kRejectedYawBranch:
      ++stats_.rsu_rejected_yaw_branch;
      break;
    default:
      ++stats_.rsu_rejected_other;
      break;
  }
  return outcome;
}

bool PoseFuser::completes_agreeing_run(const v2i::Correction& correction) {
  const auto estimate = ekf_.estimate_at(correction.sweep_time);
  if (!estimate) {
    return false;
  }
  bool continues_run = false;
  if (last_rejected_) {
    const TimeNs gap = correction.sweep_time - last_rejected_->sweep_time;
    if (gap > 0 && gap <= config_.reanchor_max_gap) {
      // Where the previous fix should be now, moved by the filter's own motion estimate.
      const double dt = to_seconds(gap);
      const double heading = estimate->state(fusion::kYaw);
      const Eigen::Vector2d expected =
          Eigen::Vector2d(last_rejected_->pose.x, last_rejected_->pose.y) +
          estimate->state(fusion::kSpeed) * dt * Eigen::Vector2d(std::cos(heading), std::sin(heading));
      continues_run = (Eigen::Vector2d(correction.pose.x, correction.pose.y) - expected).norm() <=
                      config_.reanchor_agreement_m;
    }
  }
  rejected_run_ = continues_run ? rejected_run_ + 1 : 1;
  last_rejected_ = correction;
  return rejected_run_ >= config_.reanchor_after;
}

void PoseFuser::reanchor_at(const v2i::Correction& correction) {
  const auto estimate = ekf_.estimate_at(correction.sweep_time);
  if (!estimate) {
    return;
  }
  fusion::StateEstimate anchored = *estimate;
  double yaw = correction.pose.yaw;
  if (std::abs(wrap_angle(yaw - heading_of(*estimate))) > kPi / 2) {
    yaw = wrap_angle(yaw + kPi);
  }
  const Eigen::Vector2d offset = Eigen::Rotation2Dd(yaw) * config_.ekf.reference_offset;
  anchored.time = correction.sweep_time;
  // The inverse of fusion::box_centre_from_reference: reference = centre + R(yaw) * offset.
  anchored.state(fusion::kX) = correction.pose.x + offset.x();
  anchored.state(fusion::kY) = correction.pose.y + offset.y();
  anchored.state(fusion::kYaw) = yaw;
  anchored.covariance.topLeftCorner<3, 3>() = correction.pose_covariance;
  anchored.covariance.block<3, 2>(0, 3).setZero();
  anchored.covariance.block<2, 3>(3, 0).setZero();
  ekf_.initialize(anchored);
  ++stats_.rsu_reanchors;
  rejected_run_ = 0;
  last_rejected_.reset();
}

std::optional<fusion::StateEstimate> PoseFuser::pose_at(TimeNs time) const {
  return ekf_.estimate_at(time);
}

PoseFuserStats PoseFuser::stats() const {
  PoseFuserStats out = stats_;
  out.late = ekf_.stats().late;
  out.reapplied = ekf_.stats().reapplied;
  out.ndt_restarts = ekf_.stats().ndt_restarts;
  return out;
}

}  // namespace rsu::vehicle
