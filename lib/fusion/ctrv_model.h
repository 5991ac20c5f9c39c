// SPDX-License-Identifier: Apache-2.0
// Constant turn rate and velocity (CTRV) motion model over the state [x, y, yaw, v, yaw_rate]:
// the point (x, y) moves at speed v along its heading yaw, which turns at yaw_rate. Map frame ENU,
// metres, radians, seconds (docs/design.md §3). Used by the vehicle EKF and by the RSU to carry a vehicle's
// announced pose to a LiDAR sweep time.
#pragma once

#include <Eigen/Core>

namespace rsu::fusion {

inline constexpr int kStateSize = 5;
using StateVector = Eigen::Matrix<double, kStateSize, 1>;
using StateMatrix = Eigen::Matrix<double, kStateSize, kStateSize>;

// Indices into StateVector.
inline constexpr int kX = 0;
inline constexpr int kY = 1;
inline constexpr int kYaw = 2;
inline constexpr int kSpeed = 3;
inline constexpr int kYawRate = 4;

// White-noise accelerations that drive the model (the usual CTRV noise inputs).
struct CtrvNoise {
  double accel_sigma_mps2 = 1.5;      // longitudinal acceleration: town driving, gentle braking
  double yaw_accel_sigma_rps2 = 0.6;  // change of yaw rate entering/leaving a bend
};

struct CtrvStep {
  StateVector state;
  StateMatrix jacobian;  // d(state after) / d(state before)
};

// One exact CTRV step of dt seconds (dt may be negative). Written with the chord form
// dx = v dt sinc(w dt / 2) cos(yaw + w dt / 2), which is exact for every w and has no 0/0 at w = 0,
// so straight driving needs no special case. The returned yaw is wrapped to (-pi, pi].
CtrvStep ctrv_step(const StateVector& state, double dt_s);

// Discrete process noise of one step: the accelerations enter as
// x += dt^2/2 cos(yaw) a, y += dt^2/2 sin(yaw) a, v += dt a, yaw += dt^2/2 alpha, w += dt alpha.
StateMatrix ctrv_process_noise(const StateVector& state, double dt_s, const CtrvNoise& noise);

// Carries a Gaussian (state, covariance) over dt seconds in sub-steps of at most max_step_s, so that
// the linearisation stays good over long gaps.
void ctrv_propagate(StateVector& state, StateMatrix& covariance, double dt_s, const CtrvNoise& noise,
                    double max_step_s);

}  // namespace rsu::fusion
