// SPDX-License-Identifier: Apache-2.0
// Measurement models of the vehicle EKF: what an NDT pose and an RSU correction observe of the state
// [x, y, yaw, v, yaw_rate] (the state's x, y is the vehicle's reference point).
#pragma once

#include <Eigen/Core>

#include "fusion/ctrv_model.h"
#include "fusion/pose_measurement.h"

namespace rsu::fusion {

struct PoseInnovation {
  Eigen::Vector3d residual;                       // measured minus predicted (x, y, yaw), yaw on its branch
  Eigen::Matrix<double, 3, kStateSize> jacobian;  // d(predicted measurement) / d(state)
};

// The footprint box centre of a vehicle whose reference point has the given pose; reference_offset is
// the reference point minus the box centre in the vehicle frame (as announced, docs/design.md §3).
Eigen::Vector2d box_centre_from_reference(double x, double y, double yaw,
                                          const Eigen::Vector2d& reference_offset);

// Yaw residual measured - estimate on the branch nearest the estimate: modulo 2 pi for a full heading
// (NDT), modulo pi for an RSU box, whose yaw may point backwards. Result in (-pi, pi] or [-pi/2, pi/2].
double yaw_residual(double measured_yaw, double estimated_yaw, MeasurementSource source);

// Residual and Jacobian of a pose measurement at the given state. NDT observes the reference point and
// heading directly; an RSU correction observes the box centre, reference point minus R(yaw) * offset.
PoseInnovation pose_innovation(const StateVector& state, const PoseMeasurement& measurement,
                               const Eigen::Vector2d& reference_offset);

// False for NaN/inf anywhere or a covariance that is not symmetric positive definite.
bool is_well_formed(const PoseMeasurement& measurement);

}  // namespace rsu::fusion
