// SPDX-License-Identifier: Apache-2.0
// fix_nis (integrity_monitor.h) on cases small enough to invert by hand: the innovation of an RSU fix
// (box centre, box yaw) against the vehicle's estimate of its reference point, S = H P H^T + R, and
// r^T S^-1 r written out in closed form; infinite when S is not positive definite.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "common/angles.h"
#include "vehicle/integrity_monitor.h"

namespace rsu::vehicle {
namespace fix_nis_test {

// An estimate of the reference point at (x, y, yaw), speed and yaw rate 0, with a diagonal covariance.
fusion::StateEstimate estimate_at(double x, double y, double yaw, double var_xy_x, double var_xy_y,
                                  double var_yaw) {
  fusion::StateEstimate e;
  e.state << x, y, yaw, 0.0, 0.0;
  e.covariance = fusion::StateMatrix::Identity();
  e.covariance(0, 0) = var_xy_x;
  e.covariance(1, 1) = var_xy_y;
  e.covariance(2, 2) = var_yaw;
  return e;
}

v2i::Correction fix_at(double x, double y, double yaw, double var_x, double var_y, double var_yaw) {
  v2i::Correction c;
  c.rsu_id = 7;
  c.pose = {x, y, yaw};
  c.pose_covariance = Eigen::Vector3d(var_x, var_y, var_yaw).asDiagonal();
  return c;
}

// Reference point = box centre (offset 0): H is the identity on (x, y, yaw), S = P + R, diagonal.
TEST(FixNis, WithoutOffsetIsTheSumOfSquaredOffsetsOverSummedVariances) {
  const auto own = estimate_at(10.0, 20.0, 0.3, 0.04, 0.09, 0.01);
  const auto fix = fix_at(10.3, 19.6, 0.35, 0.05, 0.07, 0.03);
  // S = diag(0.04 + 0.05, 0.09 + 0.07, 0.01 + 0.03) = diag(0.09, 0.16, 0.04); r = (0.3, -0.4, 0.05):
  // 0.09 / 0.09 + 0.16 / 0.16 + 0.0025 / 0.04 = 1 + 1 + 0.0625.
  EXPECT_NEAR(fix_nis(fix, own, Eigen::Vector2d::Zero()), 2.0625, 1e-9);
  // The fix exactly at the estimate: 0.
  EXPECT_NEAR(fix_nis(fix_at(10.0, 20.0, 0.3, 0.05, 0.07, 0.03), own, Eigen::Vector2d::Zero()), 0.0, 1e-12);
}

// Scaling both covariances by k divides the NIS by k (a unit check on S = P + R, not P alone or R alone).
TEST(FixNis, ScalesInverselyWithBothCovariances) {
  const auto own = estimate_at(0.0, 0.0, 0.0, 0.01, 0.01, 0.01);
  const auto fix = fix_at(0.2, 0.0, 0.0, 0.03, 0.03, 0.03);
  // S_xx = 0.04: 0.04 / 0.04 = 1.
  EXPECT_NEAR(fix_nis(fix, own, Eigen::Vector2d::Zero()), 1.0, 1e-12);
  const auto own4 = estimate_at(0.0, 0.0, 0.0, 0.04, 0.04, 0.04);
  const auto fix4 = fix_at(0.2, 0.0, 0.0, 0.12, 0.12, 0.12);
  EXPECT_NEAR(fix_nis(fix4, own4, Eigen::Vector2d::Zero()), 0.25, 1e-12);
}

// The reference point 1.5 m ahead of the box centre (offset = reference - centre, vehicle frame) and
// the vehicle heading north (yaw pi/2): the predicted centre is (10, 20) - R(pi/2) (1.5, 0) = (10, 18.5).
// The centre's derivative in yaw is -R'(yaw) offset = -(-1.5 sin, 1.5 cos) = (1.5, 0) at pi/2, so H's
// yaw column is (1.5, 0, 1) and, with P = R = 0.01 I,
//   S = [[0.01 + 2.25 * 0.01 + 0.01, 0, 1.5 * 0.01], [0, 0.02, 0], [0.015, 0, 0.02]]
//     = [[0.0425, 0, 0.015], [0, 0.02, 0], [0.015, 0, 0.02]].
// r = (0.2, 0.1, 0): the (x, yaw) block's inverse has (0, 0) = 0.02 / (0.0425 * 0.02 - 0.015^2)
// = 0.02 / 0.000625 = 32, so NIS = 0.04 * 32 + 0.01 / 0.02 = 1.28 + 0.5 = 1.78.
TEST(FixNis, OffsetCouplesTheYawUncertaintyIntoTheCentre) {
  const auto own = estimate_at(10.0, 20.0, kPi / 2.0, 0.01, 0.01, 0.01);
  const auto fix = fix_at(10.2, 18.6, kPi / 2.0, 0.01, 0.01, 0.01);
  EXPECT_NEAR(fix_nis(fix, own, Eigen::Vector2d(1.5, 0.0)), 1.78, 1e-9);
  // The same fix judged as if the reference were the centre is farther off: (10.2, 18.6) against
  // (10, 20): 0.04 / 0.02 + 1.96 / 0.02 = 100.
  EXPECT_NEAR(fix_nis(fix, own, Eigen::Vector2d::Zero()), 100.0, 1e-9);
}

// A box has no front: its yaw is compared on the branch nearest the estimate, modulo pi.
TEST(FixNis, BoxYawPointingBackwardsIsTheSameFix) {
  const auto own = estimate_at(0.0, 0.0, 0.2, 0.01, 0.01, 0.01);
  // r_yaw = 0.05 either way: 0.0025 / 0.02 = 0.125.
  const double forwards = fix_nis(fix_at(0.0, 0.0, 0.25, 0.01, 0.01, 0.01), own, Eigen::Vector2d::Zero());
  const double backwards =
      fix_nis(fix_at(0.0, 0.0, 0.25 - kPi, 0.01, 0.01, 0.01), own, Eigen::Vector2d::Zero());
  EXPECT_NEAR(forwards, 0.125, 1e-9);
  EXPECT_NEAR(backwards, 0.125, 1e-9);
  // Across the +-pi seam: estimate at pi - 0.01, fix at -pi + 0.02 (0.03 further on, the same heading).
  const auto seam = estimate_at(0.0, 0.0, kPi - 0.01, 0.01, 0.01, 0.01);
  EXPECT_NEAR(fix_nis(fix_at(0.0, 0.0, -kPi + 0.02, 0.01, 0.01, 0.01), seam, Eigen::Vector2d::Zero()),
              0.0009 / 0.02, 1e-9);
}

TEST(FixNis, InfiniteWhenTheSummedCovarianceIsNotPositiveDefinite) {
  const double inf = std::numeric_limits<double>::infinity();
  const auto own = estimate_at(0.0, 0.0, 0.0, 0.01, 0.01, 0.01);
  // S = 0 (the fix's covariance cancels the estimate's).
  EXPECT_EQ(fix_nis(fix_at(0.1, 0.0, 0.0, -0.01, -0.01, -0.01), own, Eigen::Vector2d::Zero()), inf);
  // S indefinite: diag(-0.99, 0.02, 0.02), even for a fix exactly at the estimate.
  EXPECT_EQ(fix_nis(fix_at(0.0, 0.0, 0.0, -1.0, 0.01, 0.01), own, Eigen::Vector2d::Zero()), inf);
  // S singular though both are positive semi-definite: a zero variance on both sides in yaw.
  const auto own_yaw_known = estimate_at(0.0, 0.0, 0.0, 0.01, 0.01, 0.0);
  EXPECT_EQ(fix_nis(fix_at(0.1, 0.0, 0.0, 0.01, 0.01, 0.0), own_yaw_known, Eigen::Vector2d::Zero()), inf);
  // A NaN covariance is no covariance.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(fix_nis(fix_at(0.1, 0.0, 0.0, nan, 0.01, 0.01), own, Eigen::Vector2d::Zero()), inf);
}

// A NaN pose never passes a chi-square gate (whatever the number, `nis <= gate` is false).
TEST(FixNis, NanPoseNeverReadsAsConsistent) {
  const auto own = estimate_at(0.0, 0.0, 0.0, 0.01, 0.01, 0.01);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double n = fix_nis(fix_at(nan, 0.0, 0.0, 0.01, 0.01, 0.01), own, Eigen::Vector2d::Zero());
  EXPECT_FALSE(n <= 1e300) << n;
}

}  // namespace fix_nis_test
}  // namespace rsu::vehicle
