#include "vehicle_client/pose_fuser.h"

namespace rsu::vehicle_client {

using fusion::MeasurementOutcome;

namespace {

bool is_accepted(MeasurementOutcome outcome) {
  return outcome == MeasurementOutcome::kAccepted || outcome == MeasurementOutcome::kInitialized;
}

}  // namespace

PoseFuser::PoseFuser(const PoseFuserConfig& config) : ekf_(config.ekf) {}

MeasurementOutcome PoseFuser::add_ndt(const Pose2& pose, const Eigen::Matrix3d& covariance, TimeNs time) {
  const MeasurementOutcome outcome = ekf_.add({time, fusion::MeasurementSource::kNdt, pose, covariance});
  is_accepted(outcome) ? ++stats_.ndt_accepted : ++stats_.ndt_rejected;
  return outcome;
}

MeasurementOutcome PoseFuser::add_rsu(const v2i::Correction& correction) {
  const MeasurementOutcome outcome = ekf_.add(
      {correction.sweep_time, fusion::MeasurementSource::kRsu, correction.pose, correction.pose_covariance});
  switch (outcome) {
    case MeasurementOutcome::kAccepted:
    case MeasurementOutcome::kInitialized:
      ++stats_.rsu_accepted;
      break;
    case MeasurementOutcome::kRejectedGate:
      ++stats_.rsu_rejected_gate;
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

std::optional<fusion::StateEstimate> PoseFuser::pose_at(TimeNs time) const { return ekf_.estimate_at(time); }

PoseFuserStats PoseFuser::stats() const {
  PoseFuserStats out = stats_;
  out.late = ekf_.stats().late;
  out.reapplied = ekf_.stats().reapplied;
  return out;
}

}  // namespace rsu::vehicle_client
