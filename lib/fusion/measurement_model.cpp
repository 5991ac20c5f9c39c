// SPDX-License-Identifier: Apache-2.0
#include "fusion/measurement_model.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "common/angles.h"

namespace rsu::fusion {

Eigen::Vector2d box_centre_from_reference(double x, double y, double yaw,
                                          const Eigen::Vector2d& reference_offset) {
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  return {x - (c * reference_offset.x() - s * reference_offset.y()),
          y - (s * reference_offset.x() + c * reference_offset.y())};
}

double yaw_residual(double measured_yaw, double estimated_yaw, MeasurementSource source) {
  const double full = wrap_angle(measured_yaw - estimated_yaw);
  if (source == MeasurementSource::kNdt) {
    return full;
  }
  // A box yaw is ambiguous by pi: take the branch nearest the estimate.
  return full - kPi * std::round(full / kPi);
}

PoseInnovation pose_innovation(const StateVector& state, const PoseMeasurement& measurement,
                               const Eigen::Vector2d& reference_offset) {
  PoseInnovation out;
  out.jacobian.setZero();
  out.jacobian(0, kX) = 1.0;
  out.jacobian(1, kY) = 1.0;
  out.jacobian(2, kYaw) = 1.0;
  const double yaw = state(kYaw);
  Eigen::Vector2d predicted(state(kX), state(kY));
  if (measurement.source == MeasurementSource::kRsu) {
    predicted = box_centre_from_reference(state(kX), state(kY), yaw, reference_offset);
    // d/dyaw of -R(yaw) * offset.
    const double c = std::cos(yaw);
    const double s = std::sin(yaw);
    out.jacobian(0, kYaw) = s * reference_offset.x() + c * reference_offset.y();
    out.jacobian(1, kYaw) = -c * reference_offset.x() + s * reference_offset.y();
  }
  out.residual.x() = measurement.pose.x - predicted.x();
  out.residual.y() = measurement.pose.y - predicted.y();
  out.residual.z() = yaw_residual(measurement.pose.yaw, yaw, measurement.source);
  return out;
}

bool is_well_formed(const PoseMeasurement& measurement) {
  const auto& p = measurement.pose;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw) ||
      !measurement.covariance.allFinite()) {
    return false;
  }
  const Eigen::Matrix3d& c = measurement.covariance;
  const double scale = c.cwiseAbs().maxCoeff();
  if (!((c - c.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) {
    return false;
  }
  const Eigen::LLT<Eigen::Matrix3d> llt(c);
  return llt.info() == Eigen::Success;
}

}  // namespace rsu::fusion
