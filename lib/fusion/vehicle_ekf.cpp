// SPDX-License-Identifier: Apache-2.0
#include "fusion/vehicle_ekf.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "common/angles.h"
#include "fusion/measurement_model.h"

namespace rsu::fusion {
namespace {

// Seconds from `from` to `to` without signed overflow for any pair of TimeNs values.
double seconds_between(TimeNs from, TimeNs to) {
  TimeNs diff = 0;
  if (__builtin_sub_overflow(to, from, &diff)) {
    return (static_cast<double>(to) - static_cast<double>(from)) * 1e-9;
  }
  return to_seconds(diff);
}

StateEstimate predict(const StateEstimate& from, TimeNs t, const VehicleEkfConfig& config) {
  StateEstimate out = from;
  ctrv_propagate(out.state, out.covariance, seconds_between(from.time, t), config.process_noise,
                 config.max_prediction_step_s);
  out.time = t;
  return out;
}

}  // namespace

const char* to_string(MeasurementOutcome outcome) {
  switch (outcome) {
    case MeasurementOutcome::kInitialized:
      return "initialized";
    case MeasurementOutcome::kAccepted:
      return "accepted";
    case MeasurementOutcome::kRejectedGate:
      return "rejected_gate";
    case MeasurementOutcome::kRejectedYawBranch:
      return "rejected_yaw_branch";
    case MeasurementOutcome::kRejectedTooOld:
      return "rejected_too_old";
    case MeasurementOutcome::kRejectedNotInitialized:
      return "rejected_not_initialized";
    case MeasurementOutcome::kRejectedInvalid:
      return "rejected_invalid";
    case MeasurementOutcome::kCount:
      break;
  }
  return "unknown";
}

std::uint64_t EkfStats::rejected() const {
  return count(MeasurementOutcome::kRejectedGate) + count(MeasurementOutcome::kRejectedYawBranch) +
         count(MeasurementOutcome::kRejectedTooOld) + count(MeasurementOutcome::kRejectedNotInitialized) +
         count(MeasurementOutcome::kRejectedInvalid);
}

VehicleEkf::VehicleEkf(const VehicleEkfConfig& config) : config_(config) {}

void VehicleEkf::initialize(const StateEstimate& start) {
  anchor_ = start;
  anchor_.state(kYaw) = wrap_angle(anchor_.state(kYaw));
  horizon_ = start.time;
  history_.clear();
  ndt_gate_run_ = 0;
  initialized_ = true;
}

void VehicleEkf::count(MeasurementOutcome outcome, int delta) {
  auto& n = stats_.by_outcome[static_cast<std::size_t>(outcome)];
  n = delta >= 0 ? n + static_cast<std::uint64_t>(delta) : n - static_cast<std::uint64_t>(-delta);
}

const StateEstimate& VehicleEkf::newest_state() const {
  return history_.empty() ? anchor_ : history_.back().posterior;
}

MeasurementOutcome VehicleEkf::start_from(const PoseMeasurement& ndt) {
  StateEstimate start;
  start.time = ndt.time;
  start.state << ndt.pose.x, ndt.pose.y, ndt.pose.yaw, 0.0, 0.0;
  start.covariance.setZero();
  start.covariance.topLeftCorner<3, 3>() = ndt.covariance;
  start.covariance(kSpeed, kSpeed) = config_.initial_speed_sigma_mps * config_.initial_speed_sigma_mps;
  start.covariance(kYawRate, kYawRate) =
      config_.initial_yaw_rate_sigma_rps * config_.initial_yaw_rate_sigma_rps;
  initialize(start);
  count(MeasurementOutcome::kInitialized, 1);
  return MeasurementOutcome::kInitialized;
}

MeasurementOutcome VehicleEkf::fuse(StateEstimate& estimate, const PoseMeasurement& m) const {
  StateEstimate predicted = predict(estimate, m.time, config_);
  const PoseInnovation innovation = pose_innovation(predicted.state, m, config_.reference_offset);
  if (m.source == MeasurementSource::kRsu &&
      std::abs(innovation.residual.z()) > config_.max_rsu_yaw_innovation_rad) {
    return MeasurementOutcome::kRejectedYawBranch;
  }
  const auto& h = innovation.jacobian;
  const Eigen::Matrix3d s = h * predicted.covariance * h.transpose() + m.covariance;
  const Eigen::LDLT<Eigen::Matrix3d> s_ldlt(s);
  if (s_ldlt.info() != Eigen::Success) {
    return MeasurementOutcome::kRejectedInvalid;
  }
  const double distance_sq = innovation.residual.dot(s_ldlt.solve(innovation.residual));
  // Written so that NaN fails the gate too.
  if (!(distance_sq >= 0.0 && distance_sq <= config_.gate_chi2)) {
    return MeasurementOutcome::kRejectedGate;
  }
  // K = P H^T S^-1, via the symmetric solve S K^T = H P.
  const Eigen::Matrix<double, kStateSize, 3> gain = s_ldlt.solve(h * predicted.covariance).transpose();
  predicted.state += gain * innovation.residual;
  predicted.state(kYaw) = wrap_angle(predicted.state(kYaw));
  // Joseph form: stays symmetric positive semi-definite under rounding.
  const StateMatrix i_kh = StateMatrix::Identity() - gain * h;
  predicted.covariance =
      i_kh * predicted.covariance * i_kh.transpose() + gain * m.covariance * gain.transpose();
  predicted.covariance = 0.5 * (predicted.covariance + predicted.covariance.transpose()).eval();
  estimate = predicted;
  return MeasurementOutcome::kAccepted;
}

MeasurementOutcome VehicleEkf::add(const PoseMeasurement& m) {
  if (!is_well_formed(m)) {
    count(MeasurementOutcome::kRejectedInvalid, 1);
    return MeasurementOutcome::kRejectedInvalid;
  }
  if (!initialized_) {
    if (m.source != MeasurementSource::kNdt) {
      count(MeasurementOutcome::kRejectedNotInitialized, 1);
      return MeasurementOutcome::kRejectedNotInitialized;
    }
    return start_from(m);
  }
  const TimeNs newest = history_.empty() ? anchor_.time : history_.back().measurement.time;
  if (m.time < horizon_) {
    count(MeasurementOutcome::kRejectedTooOld, 1);
    return MeasurementOutcome::kRejectedTooOld;
  }
  if (seconds_between(newest, m.time) > to_seconds(config_.restart_after_gap)) {
    // No measurement for so long that the prediction means nothing: restart from a full pose, and
    // refuse an RSU box until then (its yaw branch cannot be chosen without a heading).
    if (m.source != MeasurementSource::kNdt) {
      count(MeasurementOutcome::kRejectedNotInitialized, 1);
      return MeasurementOutcome::kRejectedNotInitialized;
    }
    initialized_ = false;
    return add(m);
  }
  if (m.time >= newest) {
    HistoryEntry entry{m, MeasurementOutcome::kAccepted, newest_state()};
    entry.outcome = fuse(entry.posterior, m);
    if (entry.outcome == MeasurementOutcome::kRejectedGate && m.source == MeasurementSource::kNdt) {
      if (++ndt_gate_run_ >= std::max(config_.ndt_restart_after_rejections, 1)) {
        // Locked out (see VehicleEkfConfig::ndt_restart_after_rejections): restart at this pose.
        ++stats_.ndt_restarts;
        return start_from(m);
      }
    } else if (entry.outcome == MeasurementOutcome::kAccepted) {
      ndt_gate_run_ = 0;
    }
    count(entry.outcome, 1);
    history_.push_back(entry);
    prune();
    return entry.outcome;
  }
  // Late: insert after every kept measurement of the same or an earlier time, then redo the rest.
  ++stats_.late;
  const auto position =
      std::upper_bound(history_.begin(), history_.end(), m.time,
                       [](TimeNs t, const HistoryEntry& e) { return t < e.measurement.time; });
  const auto index = static_cast<std::size_t>(position - history_.begin());
  history_.insert(position, HistoryEntry{m, MeasurementOutcome::kCount, StateEstimate{}});
  replay_from(index);
  const MeasurementOutcome outcome = history_[index].outcome;
  if (outcome == MeasurementOutcome::kAccepted) {
    ndt_gate_run_ = 0;
  }
  prune();
  return outcome;
}

std::size_t VehicleEkf::reweigh_ndt(const std::map<TimeNs, Eigen::Matrix3d>& covariances) {
  std::optional<std::size_t> first;
  std::size_t changed = 0;
  for (std::size_t k = 0; k < history_.size(); ++k) {
    PoseMeasurement& m = history_[k].measurement;
    const auto it = covariances.find(m.time);
    if (m.source != MeasurementSource::kNdt || it == covariances.end() || it->second == m.covariance) {
      continue;
    }
    m.covariance = it->second;
    first = first.value_or(k);
    ++changed;
  }
  if (first) {
    replay_from(*first);
  }
  return changed;
}

void VehicleEkf::replay_from(std::size_t index) {
  StateEstimate state = index == 0 ? anchor_ : history_[index - 1].posterior;
  for (std::size_t k = index; k < history_.size(); ++k) {
    HistoryEntry& entry = history_[k];
    const MeasurementOutcome outcome = fuse(state, entry.measurement);
    if (entry.outcome == MeasurementOutcome::kCount) {  // the newly inserted one
      count(outcome, 1);
    } else {
      ++stats_.reapplied;
      if (outcome != entry.outcome) {
        count(entry.outcome, -1);
        count(outcome, 1);
      }
    }
    entry.outcome = outcome;
    entry.posterior = state;
  }
}

void VehicleEkf::prune() {
  const TimeNs newest = history_.back().measurement.time;
  const std::size_t max_entries = std::max<std::size_t>(config_.max_history, 1);
  while (!history_.empty() &&
         (history_.size() > max_entries ||
          seconds_between(history_.front().measurement.time, newest) > to_seconds(config_.history_window))) {
    anchor_ = history_.front().posterior;
    horizon_ = history_.front().measurement.time;
    history_.pop_front();
  }
}

std::optional<StateEstimate> VehicleEkf::latest() const {
  if (!initialized_) {
    return std::nullopt;
  }
  return newest_state();
}

std::optional<StateEstimate> VehicleEkf::estimate_at(TimeNs t) const {
  if (!initialized_) {
    return std::nullopt;
  }
  const auto after =
      std::upper_bound(history_.begin(), history_.end(), t,
                       [](TimeNs time, const HistoryEntry& e) { return time < e.measurement.time; });
  const StateEstimate& base = after == history_.begin() ? anchor_ : std::prev(after)->posterior;
  return predict(base, t, config_);
}

}  // namespace rsu::fusion
