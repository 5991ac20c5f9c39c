#include "vehicle/vehicle_core.h"

namespace rsu::vehicle {

VehicleCore::VehicleCore(const VehicleCoreConfig& config) : config_(config), fuser_(config.fuser) {}

NdtStep VehicleCore::on_ndt(const NdtPose& ndt) {
  fuser_.add_ndt(ndt.pose, ndt.covariance, ndt.time);
  NdtStep step;
  step.fused = fuser_.pose_at(ndt.time);
  step.announce = state_to_announce(ndt, step.fused);
  return step;
}

CorrectionStep VehicleCore::on_correction(const v2i::Correction& correction) {
  CorrectionStep step;
  if (!config_.fuse_corrections) {
    return step;
  }
  step.outcome = fuser_.add_rsu(correction);
  if (*step.outcome == fusion::MeasurementOutcome::kAccepted) {
    step.fused = fuser_.pose_at(correction.sweep_time);
  }
  return step;
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
