// The vehicle's side of RSU-assisted localization as one pure loop (no sockets, threads or clocks; the
// caller passes the data in with their times): its own NDT poses and the RSU corrections it accepted
// (CorrectionFilter) are fused (PoseFuser over lib/fusion's EKF), and each NDT pose yields the state to
// announce next (Announcer sends it). rsu-vehicle and the rsu_vehicle_client library are I/O around it.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "common/pose.h"
#include "common/time.h"
#include "fusion/vehicle_ekf.h"
#include "v2i/messages.h"
#include "vehicle/announcer.h"
#include "vehicle/pose_fuser.h"

namespace rsu::vehicle {

// One pose of the vehicle's own NDT scan matching: its reference point, full heading, covariance.
struct NdtPose {
  TimeNs time = 0;
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // (x, y, yaw)
};

struct VehicleCoreConfig {
  PoseFuserConfig fuser;
  // False: corrections are recorded but not fused, so the output is the NDT-only filter (a baseline).
  bool fuse_corrections = true;
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

// What became of a correction.
struct CorrectionStep {
  std::optional<fusion::MeasurementOutcome> outcome;  // empty when corrections are not fused
  std::optional<fusion::StateEstimate> fused;         // at its sweep time, when it was fused
  const char* label() const { return outcome ? fusion::to_string(*outcome) : "not_fused"; }
};

class VehicleCore {
 public:
  explicit VehicleCore(const VehicleCoreConfig& config = {});

  NdtStep on_ndt(const NdtPose& ndt);
  CorrectionStep on_correction(const v2i::Correction& correction);

  std::optional<fusion::StateEstimate> pose_at(TimeNs time) const { return fuser_.pose_at(time); }
  PoseFuserStats fuser_stats() const { return fuser_.stats(); }

 private:
  VehicleState state_to_announce(const NdtPose& ndt, const std::optional<fusion::StateEstimate>& fused) const;

  VehicleCoreConfig config_;
  PoseFuser fuser_;
};

}  // namespace rsu::vehicle
