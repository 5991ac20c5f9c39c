// SPDX-License-Identifier: Apache-2.0
#include "tracking/vehicle_hypothesis.h"

#include <cmath>

#include "fusion/ctrv_model.h"
#include "fusion/measurement_model.h"

namespace rsu::tracking {

VehicleHypothesis predict_hypothesis(const v2i::VehicleAnnouncement& a, TimeNs sweep_time,
                                     const HypothesisConfig& config) {
  namespace f = rsu::fusion;
  f::StateVector state;
  state << a.pose.x, a.pose.y, a.pose.yaw, a.speed_mps.value_or(0.0), a.yaw_rate_rps.value_or(0.0);
  f::StateMatrix covariance = f::StateMatrix::Zero();
  covariance.topLeftCorner<3, 3>() = a.pose_covariance;
  const double speed_sigma = a.speed_mps ? config.known_speed_sigma_mps : config.unknown_speed_sigma_mps;
  const double yaw_rate_sigma =
      a.yaw_rate_rps ? config.known_yaw_rate_sigma_rps : config.unknown_yaw_rate_sigma_rps;
  covariance(f::kSpeed, f::kSpeed) = speed_sigma * speed_sigma;
  covariance(f::kYawRate, f::kYawRate) = yaw_rate_sigma * yaw_rate_sigma;

  // An unknown speed enters through the Jacobian along the heading only: a vehicle moves forwards or
  // backwards, not sideways, so the gate stretches along the lane and not into the next one.
  TimeNs dt_ns = 0;
  const double dt_s = __builtin_sub_overflow(sweep_time, a.generation_time, &dt_ns)
                          ? (static_cast<double>(sweep_time) - static_cast<double>(a.generation_time)) * 1e-9
                          : to_seconds(dt_ns);
  const f::CtrvNoise noise{config.accel_sigma_mps2, config.yaw_accel_sigma_rps2};
  f::ctrv_propagate(state, covariance, dt_s, noise, 0.1);

  // Reference point -> box centre: c = p - R(yaw) * offset.
  const double yaw = state(f::kYaw);
  const Eigen::Vector2d& r = a.reference_offset;
  Eigen::Matrix<double, 3, 3> to_centre = Eigen::Matrix3d::Identity();
  to_centre(0, 2) = std::sin(yaw) * r.x() + std::cos(yaw) * r.y();
  to_centre(1, 2) = -std::cos(yaw) * r.x() + std::sin(yaw) * r.y();

  VehicleHypothesis out;
  out.vehicle_id = a.vehicle_id;
  out.centre = f::box_centre_from_reference(state(f::kX), state(f::kY), yaw, r);
  out.yaw = yaw;
  out.covariance = to_centre * covariance.topLeftCorner<3, 3>() * to_centre.transpose();
  out.size = a.size;
  return out;
}

}  // namespace rsu::tracking
