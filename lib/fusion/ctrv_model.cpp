// SPDX-License-Identifier: Apache-2.0
#include "fusion/ctrv_model.h"

#include <algorithm>
#include <cmath>

#include "common/angles.h"

namespace rsu::fusion {
namespace {

constexpr int kMaxSubSteps = 1000;

// sin(h) / h and its derivative, with Taylor series near 0 where the closed forms lose precision.
double sinc(double h) {
  if (std::abs(h) < 1e-4) {
    return 1.0 - h * h / 6.0;
  }
  return std::sin(h) / h;
}

double sinc_derivative(double h) {
  if (std::abs(h) < 1e-4) {
    return -h / 3.0 + h * h * h / 30.0;
  }
  return (h * std::cos(h) - std::sin(h)) / (h * h);
}

}  // namespace

CtrvStep ctrv_step(const StateVector& state, double dt_s) {
  const double yaw = state(kYaw);
  const double v = state(kSpeed);
  const double w = state(kYawRate);
  const double half_turn = 0.5 * w * dt_s;
  const double chord_heading = yaw + half_turn;
  const double s = sinc(half_turn);
  const double ds = sinc_derivative(half_turn);
  const double c = std::cos(chord_heading);
  const double sn = std::sin(chord_heading);
  const double travel = v * dt_s;  // arc length

  CtrvStep out;
  out.state = state;
  out.state(kX) += travel * s * c;
  out.state(kY) += travel * s * sn;
  out.state(kYaw) = wrap_angle(yaw + w * dt_s);

  out.jacobian.setIdentity();
  out.jacobian(kX, kYaw) = -travel * s * sn;
  out.jacobian(kY, kYaw) = travel * s * c;
  out.jacobian(kX, kSpeed) = dt_s * s * c;
  out.jacobian(kY, kSpeed) = dt_s * s * sn;
  // d/dw through half_turn = w dt / 2 (both the sinc factor and the chord heading depend on it).
  out.jacobian(kX, kYawRate) = travel * 0.5 * dt_s * (ds * c - s * sn);
  out.jacobian(kY, kYawRate) = travel * 0.5 * dt_s * (ds * sn + s * c);
  out.jacobian(kYaw, kYawRate) = dt_s;
  return out;
}

StateMatrix ctrv_process_noise(const StateVector& state, double dt_s, const CtrvNoise& noise) {
  const double half_dt2 = 0.5 * dt_s * dt_s;
  Eigen::Matrix<double, kStateSize, 2> input;
  input.setZero();
  input(kX, 0) = half_dt2 * std::cos(state(kYaw));
  input(kY, 0) = half_dt2 * std::sin(state(kYaw));
  input(kSpeed, 0) = dt_s;
  input(kYaw, 1) = half_dt2;
  input(kYawRate, 1) = dt_s;
  const Eigen::Vector2d variances(noise.accel_sigma_mps2 * noise.accel_sigma_mps2,
                                  noise.yaw_accel_sigma_rps2 * noise.yaw_accel_sigma_rps2);
  return input * variances.asDiagonal() * input.transpose();
}

void ctrv_propagate(StateVector& state, StateMatrix& covariance, double dt_s, const CtrvNoise& noise,
                    double max_step_s) {
  if (dt_s == 0.0 || !std::isfinite(dt_s)) {
    return;
  }
  const double step_limit = max_step_s > 0.0 ? max_step_s : std::abs(dt_s);
  // The step count is capped so that an absurd gap (a bad timestamp) costs bounded time.
  const double wanted_steps = std::ceil(std::abs(dt_s) / step_limit - 1e-9);
  const int steps = static_cast<int>(std::clamp(wanted_steps, 1.0, static_cast<double>(kMaxSubSteps)));
  const double h = dt_s / steps;
  for (int i = 0; i < steps; ++i) {
    const StateMatrix q = ctrv_process_noise(state, h, noise);
    const CtrvStep step = ctrv_step(state, h);
    covariance = step.jacobian * covariance * step.jacobian.transpose() + q;
    covariance = 0.5 * (covariance + covariance.transpose()).eval();
    state = step.state;
  }
}

}  // namespace rsu::fusion
