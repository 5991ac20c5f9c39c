// SPDX-License-Identifier: Apache-2.0
#include "fusion/ctrv_model.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "common/angles.h"

namespace rsu::fusion {
namespace {

StateVector make_state(double x, double y, double yaw, double v, double w) {
  StateVector s;
  s << x, y, yaw, v, w;
  return s;
}

// Independent geometry: a point moving at speed v on a circle of radius v / w.
Eigen::Vector2d on_circle(const StateVector& s0, double t) {
  const double r = s0(kSpeed) / s0(kYawRate);
  const double cx = s0(kX) - r * std::sin(s0(kYaw));
  const double cy = s0(kY) + r * std::cos(s0(kYaw));
  const double yaw = s0(kYaw) + s0(kYawRate) * t;
  return {cx + r * std::sin(yaw), cy - r * std::cos(yaw)};
}

TEST(Ctrv, TurningFollowsTheCircle) {
  for (const double w : {0.5, -0.8, 2.0}) {
    const StateVector s0 = make_state(3.0, -2.0, 1.1, 7.0, w);
    for (const double dt : {0.01, 0.1, 1.0, -0.3}) {
      const CtrvStep step = ctrv_step(s0, dt);
      const Eigen::Vector2d expected = on_circle(s0, dt);
      EXPECT_NEAR(step.state(kX), expected.x(), 1e-9) << "w " << w << " dt " << dt;
      EXPECT_NEAR(step.state(kY), expected.y(), 1e-9);
      EXPECT_NEAR(angle_distance(step.state(kYaw), 1.1 + w * dt), 0.0, 1e-12);
      EXPECT_EQ(step.state(kSpeed), 7.0);
      EXPECT_EQ(step.state(kYawRate), w);
    }
  }
  // A full turn returns to the start.
  const StateVector s0 = make_state(3.0, -2.0, 1.1, 7.0, 0.5);
  const CtrvStep full = ctrv_step(s0, 2.0 * kPi / 0.5);
  EXPECT_NEAR(full.state(kX), 3.0, 1e-9);
  EXPECT_NEAR(full.state(kY), -2.0, 1e-9);
}

TEST(Ctrv, StraightAndNearlyStraight) {
  for (const double w : {0.0, 1e-12, -1e-7}) {
    const StateVector s0 = make_state(1.0, 2.0, 0.6, 12.0, w);
    const CtrvStep step = ctrv_step(s0, 0.5);
    EXPECT_NEAR(step.state(kX), 1.0 + 6.0 * std::cos(0.6), 1e-6);
    EXPECT_NEAR(step.state(kY), 2.0 + 6.0 * std::sin(0.6), 1e-6);
  }
}

TEST(Ctrv, JacobianMatchesFiniteDifferences) {
  for (const double w : {0.0, 1e-7, 0.7, -1.3}) {
    for (const double dt : {0.1, 0.8, -0.2}) {
      const StateVector s0 = make_state(4.0, 5.0, -2.5, 9.0, w);
      const StateMatrix jacobian = ctrv_step(s0, dt).jacobian;
      const double h = 1e-6;
      for (int j = 0; j < kStateSize; ++j) {
        StateVector plus = s0;
        StateVector minus = s0;
        plus(j) += h;
        minus(j) -= h;
        StateVector diff = ctrv_step(plus, dt).state - ctrv_step(minus, dt).state;
        diff(kYaw) = wrap_angle(diff(kYaw));
        const StateVector numeric = diff / (2.0 * h);
        for (int i = 0; i < kStateSize; ++i) {
          EXPECT_NEAR(jacobian(i, j), numeric(i), 1e-5)
              << "d" << i << "/d" << j << " w " << w << " dt " << dt;
        }
      }
    }
  }
}

TEST(Ctrv, ProcessNoiseIsSymmetricPositiveSemiDefiniteAndGrowsWithTime) {
  const StateVector s = make_state(0, 0, 0.4, 10, 0.1);
  const CtrvNoise noise{1.5, 0.6};
  const StateMatrix q1 = ctrv_process_noise(s, 0.1, noise);
  const StateMatrix q2 = ctrv_process_noise(s, 0.2, noise);
  EXPECT_NEAR((q1 - q1.transpose()).norm(), 0.0, 1e-15);
  Eigen::SelfAdjointEigenSolver<StateMatrix> eig(q1);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-15);
  // Speed variance from white acceleration over dt: (sigma_a * dt)^2.
  EXPECT_NEAR(q1(kSpeed, kSpeed), (1.5 * 0.1) * (1.5 * 0.1), 1e-15);
  EXPECT_GT(q2.trace(), q1.trace());
}

TEST(Ctrv, SubSteppedPropagationKeepsTheExactMean) {
  StateVector s = make_state(3.0, -2.0, 1.1, 7.0, 0.5);
  const StateVector s0 = s;
  StateMatrix p = StateMatrix::Identity() * 0.01;
  ctrv_propagate(s, p, 1.3, CtrvNoise{}, 0.05);
  const Eigen::Vector2d expected = on_circle(s0, 1.3);
  EXPECT_NEAR(s(kX), expected.x(), 1e-9);
  EXPECT_NEAR(s(kY), expected.y(), 1e-9);
  EXPECT_GT(p(kX, kX), 0.01);  // uncertainty grew
  EXPECT_NEAR((p - p.transpose()).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace rsu::fusion
