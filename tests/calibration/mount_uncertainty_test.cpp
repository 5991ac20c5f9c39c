// SPDX-License-Identifier: Apache-2.0
// mount_uncertainty (mount_verdict.h) on diagonal informations whose inverse, weakest directions and
// information ratio are written out here; and MountReference::error_at_radius (mount_reference.h): the
// largest horizontal displacement of a fix at the coverage radius under a known motion of the mount, and
// its sigma, in closed form for translations and for rotations about one axis.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "calibration/mount_reference.h"
#include "calibration/mount_verdict.h"
#include "common/angles.h"

namespace rsu::calibration {
namespace mount_uncertainty_direct_test {

// sigmas of (dt, w): 1, 2, 0.5 cm and 1, 2, 0.5 mrad.
PlaneFit diagonal_fit() {
  PlaneFit fit;
  const double sigma[6] = {0.01, 0.02, 0.005, 1e-3, 2e-3, 5e-4};
  for (int i = 0; i < 6; ++i)
    fit.information(i, i) = 1.0 / (sigma[i] * sigma[i]);
  return fit;
}

TEST(MountUncertaintyDirect, DiagonalInformationInvertsPlusTheFloor) {
  const ModelFloor floor;  // 5 mm, 0.01 deg
  const double fp = 0.005 * 0.005;
  const double fa = deg_to_rad(0.01) * deg_to_rad(0.01);
  const MountUncertainty u = mount_uncertainty(diagonal_fit(), Pose3{}, floor);
  // At a level pose facing east, (roll, pitch, yaw) move with (w_x, w_y, w_z): the covariance is the
  // information's inverse plus the floor on the diagonal, and nothing off it.
  const double expected[6] = {1e-4 + fp, 4e-4 + fp, 2.5e-5 + fp, 1e-6 + fa, 4e-6 + fa, 2.5e-7 + fa};
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(u.covariance(i, i), expected[i], 1e-9 * expected[i]) << i;
    for (int j = 0; j < 6; ++j) {
      if (j != i) {
        EXPECT_NEAR(u.covariance(i, j), 0.0, 1e-15) << i << ", " << j;
      }
    }
  }
  // The weakest: along y (2 cm) and about y (2 mrad), the statistics' alone (no floor).
  EXPECT_NEAR(u.weakest_position_sigma_m, 0.02, 1e-12);
  EXPECT_NEAR(std::abs(u.weakest_position_direction.y()), 1.0, 1e-12);
  EXPECT_NEAR(u.weakest_rotation_sigma_rad, 2e-3, 1e-15);
  EXPECT_NEAR(std::abs(u.weakest_rotation_axis.y()), 1.0, 1e-12);
  // Information in m^-2 with the angles at 10 m: positions 1e4, 2500, 4e4; angles 1e6 / 100 = 1e4,
  // 2.5e5 / 100 = 2500, 4e6 / 100 = 4e4. Smallest over largest: 2500 / 4e4 = 0.0625.
  EXPECT_NEAR(u.information_ratio, 0.0625, 1e-12);
}

// Facing north (yaw 90 deg) a rotation about map x tilts the sensor about its own -y: pitch = -w_x, and
// one about map y is its roll: var(roll) = var(w_y), var(pitch) = var(w_x).
TEST(MountUncertaintyDirect, AnglesAreCarriedToTheMountsRollPitchYaw) {
  ModelFloor none;
  none.position_sigma_m = 0.0;
  none.angle_sigma_rad = 0.0;
  Pose3 north;
  north.yaw = kPi / 2.0;
  const MountUncertainty u = mount_uncertainty(diagonal_fit(), north, none);
  EXPECT_NEAR(u.covariance(3, 3), 4e-6, 1e-12);    // roll: w_y's
  EXPECT_NEAR(u.covariance(4, 4), 1e-6, 1e-12);    // pitch: w_x's
  EXPECT_NEAR(u.covariance(5, 5), 2.5e-7, 1e-13);  // yaw
  EXPECT_NEAR(u.covariance(0, 0), 1e-4, 1e-12);
}

TEST(MountUncertaintyDirect, FreeDirectionHasInfiniteSigma) {
  const double inf = std::numeric_limits<double>::infinity();
  PlaneFit free = diagonal_fit();
  free.information(0, 0) = 0.0;  // nothing holds x
  for (const PlaneFit& fit : {free, PlaneFit{}}) {
    const MountUncertainty u = mount_uncertainty(fit, Pose3{});
    EXPECT_EQ(u.weakest_position_sigma_m, inf);
    EXPECT_EQ(u.weakest_rotation_sigma_rad, inf);
    EXPECT_EQ(u.covariance(0, 0), inf);
    EXPECT_EQ(u.information_ratio, 0.0);
  }
}

// A level mount (yaw `yaw`), fixes 50 m out and 6 m below the sensor.
MountReference reference(double yaw) {
  return MountReference(std::vector<std::vector<lidar::LidarPoint>>{}, Pose3{0, 0, 6.0, 0, 0, yaw}, 50.0, 6.0,
                        MountMonitorConfig{});
}

Matrix6d diagonal6(const Vector6d& variances) {
  return variances.asDiagonal();
}

TEST(MountErrorAtRadius, TranslationMovesEveryFixByItsHorizontalPart) {
  const MountReference r = reference(0.0);
  Vector6d v;
  v << 1e-4, 1e-4, 1e-4, 0, 0, 0;
  // (3, 4, 0) cm: 5 cm everywhere; the sigma along it 1 cm (isotropic).
  const auto [error, sigma] = r.error_at_radius(Pose3{0.03, 0.04, 0.0, 0, 0, 0}, diagonal6(v));
  EXPECT_NEAR(error, 0.05, 1e-12);
  EXPECT_NEAR(sigma, 0.01, 1e-12);
  // Up by 10 cm: no horizontal error; the sigma is the larger horizontal one (2 cm along x here).
  v << 4e-4, 1e-4, 1e-4, 0, 0, 0;
  const auto [up, up_sigma] = r.error_at_radius(Pose3{0.0, 0.0, 0.1, 0, 0, 0}, diagonal6(v));
  EXPECT_NEAR(up, 0.0, 1e-12);
  EXPECT_NEAR(up_sigma, 0.02, 1e-12);
}

// The motion is in the sensor frame: facing north, the sensor's x is the map's y; its x sigma (2 cm)
// is the error's sigma.
TEST(MountErrorAtRadius, SensorFrameMotionIsCarriedIntoTheMap) {
  const MountReference r = reference(kPi / 2.0);
  Vector6d v;
  v << 4e-4, 1e-4, 1e-4, 0, 0, 0;
  const auto [error, sigma] = r.error_at_radius(Pose3{0.05, 0.0, 0.0, 0, 0, 0}, diagonal6(v));
  EXPECT_NEAR(error, 0.05, 1e-12);
  EXPECT_NEAR(sigma, 0.02, 1e-12);
}

// A yaw of 1 mrad turns every fix at 50 m by the chord 2 x 50 sin(0.5 mrad). To first order w x p is
// 50 w_z along the tangent at the fix, which the chord leaves at half the turn (0.5 mrad): a yaw sigma of
// 1 mrad gives 5 cm along the tangent, 5 cos(0.5 mrad) cm along the error.
TEST(MountErrorAtRadius, YawMovesFixesAlongTheCircle) {
  const MountReference r = reference(0.0);
  Vector6d v;
  v << 0, 0, 0, 0, 0, 1e-6;
  const auto [error, sigma] = r.error_at_radius(Pose3{0, 0, 0, 0, 0, 1e-3}, diagonal6(v));
  EXPECT_NEAR(error, 100.0 * std::sin(0.5e-3), 1e-12);
  EXPECT_NEAR(sigma, 0.05 * std::cos(0.5e-3), 1e-12);
}

// A roll a about x moves a fix p = (50 cos phi, 50 sin phi, -6) by (0, p_y (cos a - 1) + 6 sin a, ...)
// horizontally: largest at p_y = -50 (phi = 270 deg, on the 5 deg grid): 50 (1 - cos a) + 6 sin a.
TEST(MountErrorAtRadius, RollMovesTheFixesBelowSideways) {
  const MountReference r = reference(0.0);
  const double a = 0.01;
  const auto [error, sigma] = r.error_at_radius(Pose3{0, 0, 0, a, 0, 0}, Matrix6d::Zero());
  EXPECT_NEAR(error, 50.0 * (1.0 - std::cos(a)) + 6.0 * std::sin(a), 1e-12);
  EXPECT_EQ(sigma, 0.0);
}

}  // namespace mount_uncertainty_direct_test
}  // namespace rsu::calibration
