// SPDX-License-Identifier: Apache-2.0
// Vehicle-side extended Kalman filter over [x, y, yaw, v, yaw_rate] (CTRV model) fusing the vehicle's
// NDT pose with RSU corrections (the paper's Section 4 fusion, with its open problems handled: yaw
// modulo pi, off-by-90 deg boxes, late corrections). Pure computation: time comes with the data.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>

#include "common/pose.h"
#include "common/time.h"
#include "fusion/ctrv_model.h"
#include "fusion/pose_measurement.h"
#include "fusion/vehicle_ekf_config.h"

namespace rsu::fusion {

enum class MeasurementOutcome : std::uint8_t {
  kInitialized,             // the first full-heading pose started the filter
  kAccepted,                // fused
  kRejectedGate,            // innovation outside the chi-square gate
  kRejectedYawBranch,       // RSU box yaw about 90 deg off the estimate
  kRejectedTooOld,          // older than the kept history
  kRejectedNotInitialized,  // an RSU fix before any full-heading pose: its yaw cannot start the filter
  kRejectedInvalid,         // NaN/inf, or a covariance that is not symmetric positive definite
  kCount,
};

const char* to_string(MeasurementOutcome outcome);

struct EkfStats {
  // Per outcome; counts reflect the current decision for measurements still in history (a measurement
  // re-gated after a late insertion moves between counts).
  std::array<std::uint64_t, static_cast<std::size_t>(MeasurementOutcome::kCount)> by_outcome{};
  std::uint64_t late = 0;          // arrived older than the newest measurement already processed
  std::uint64_t reapplied = 0;     // measurement updates redone because a late one was inserted before them
  std::uint64_t ndt_restarts = 0;  // restarts at an NDT pose after a run of gate-refused ones (lock-out)

  std::uint64_t count(MeasurementOutcome o) const { return by_outcome[static_cast<std::size_t>(o)]; }
  std::uint64_t accepted() const {
    return count(MeasurementOutcome::kAccepted) + count(MeasurementOutcome::kInitialized);
  }
  std::uint64_t rejected() const;
};

struct StateEstimate {
  TimeNs time = 0;
  StateVector state = StateVector::Zero();
  StateMatrix covariance = StateMatrix::Identity();

  Pose2 pose() const { return {state(kX), state(kY), state(kYaw)}; }
};

class VehicleEkf {
 public:
  explicit VehicleEkf(const VehicleEkfConfig& config = {});

  // Starts (or restarts) the filter from a known state, dropping all history.
  void initialize(const StateEstimate& start);

  // Fuses one measurement. One older than the newest processed is inserted in time order and the
  // later measurements are re-applied, so the result equals in-order processing.
  MeasurementOutcome add(const PoseMeasurement& measurement);

  // Gives the kept NDT poses at the times `covariances` names the covariance it gives for them, and
  // redoes the filter from the first one changed, as if they had come so: for a weighting decided
  // before a late measurement showed it wrong (vehicle/vehicle_core.h). Returns how many changed.
  std::size_t reweigh_ndt(const std::map<TimeNs, Eigen::Matrix3d>& covariances);

  // The estimate at time t, predicted from the latest state at or before t (backwards from the oldest
  // kept state if t is older still). Does not change the filter. Empty before initialisation.
  std::optional<StateEstimate> estimate_at(TimeNs t) const;

  // The newest state, at the time of the newest fused measurement.
  std::optional<StateEstimate> latest() const;

  bool initialized() const { return initialized_; }
  const EkfStats& stats() const { return stats_; }
  const VehicleEkfConfig& config() const { return config_; }

 private:
  struct HistoryEntry {
    PoseMeasurement measurement;
    MeasurementOutcome outcome = MeasurementOutcome::kAccepted;
    StateEstimate posterior;  // after this measurement (unchanged from before it when rejected)
  };

  MeasurementOutcome start_from(const PoseMeasurement& ndt);
  MeasurementOutcome fuse(StateEstimate& estimate, const PoseMeasurement& m) const;
  void replay_from(std::size_t index);
  void prune();
  void count(MeasurementOutcome outcome, int delta);
  const StateEstimate& newest_state() const;

  VehicleEkfConfig config_;
  bool initialized_ = false;
  StateEstimate anchor_;  // the state just before history_.front()
  TimeNs horizon_ = 0;    // measurements older than this are refused (the newest one folded into anchor_)
  std::deque<HistoryEntry> history_;
  int ndt_gate_run_ = 0;  // NDT poses refused by the gate in a row, nothing accepted since
  EkfStats stats_;
};

}  // namespace rsu::fusion
