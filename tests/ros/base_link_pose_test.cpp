// SPDX-License-Identifier: Apache-2.0
// An RSU fix as the vehicle's base_link pose (lib/ros/base_link_pose.h), checked against a vehicle whose
// base_link pose the test sets: the box centre and the RSU's folded yaw are made from it here with plain
// trigonometry, and the stated covariance against the spread of many fixes drawn from the RSU's.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ros/base_link_pose.h"

namespace rsu::ros {
namespace {

constexpr double kPi = std::numbers::pi;
const Eigen::Vector2d kOffset{-1.4, 0.1};  // base_link minus box centre, vehicle frame

std::array<double, 4> yaw_quaternion(double yaw) {
  return {0.0, 0.0, std::sin(yaw / 2), std::cos(yaw / 2)};
}

// The RSU's fix of a vehicle whose base_link is at (x, y) heading `heading`: the box centre, the yaw
// folded into [-pi/2, pi/2) as a rectangle's, the covariance `cov` over (x, y, yaw).
StampedPose rsu_fix(double x, double y, double heading, const Eigen::Matrix3d& cov, TimeNs stamp) {
  const double cx = x - (std::cos(heading) * kOffset.x() - std::sin(heading) * kOffset.y());
  const double cy = y - (std::sin(heading) * kOffset.x() + std::cos(heading) * kOffset.y());
  double folded = std::fmod(heading + kPi / 2, kPi);
  folded = (folded < 0 ? folded + kPi : folded) - kPi / 2;
  StampedPose f;
  f.stamp = stamp;
  f.pose.position = {cx, cy, 0.0};
  f.pose.orientation = yaw_quaternion(folded);
  const std::array<int, 3> idx = {0, 1, 5};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      f.pose.covariance[static_cast<std::size_t>(idx[i] * 6 + idx[j])] = cov(i, j);
  return f;
}

StampedPose own_pose(double heading, double z, double z_variance, TimeNs stamp) {
  StampedPose p;
  p.stamp = stamp;
  p.pose.position = {0.0, 0.0, z};  // x, y of the own pose are not used
  p.pose.orientation = yaw_quaternion(heading);
  p.pose.covariance[2 * 6 + 2] = z_variance;
  return p;
}

Eigen::Matrix3d rsu_covariance() {
  Eigen::Matrix3d c;
  c << 0.010, 0.002, 0.0004, 0.002, 0.006, -0.0003, 0.0004, -0.0003, 0.0016;  // yaw sigma 0.04 rad
  return c;
}

TEST(BaseLinkPose, ResolvesTheYawWithTheOwnHeadingAndMovesToBaseLink) {
  const TimeNs t = 1'700'000'000'000'000'000;
  for (const double heading : {0.2, 1.4, 3.05, -3.05, -1.7, kPi / 2 + 0.1}) {
    const StampedPose fix = rsu_fix(25.0, -4.0, heading, rsu_covariance(), t);
    // The own heading 0.2 rad off, the nearest of three own poses in time 30 ms from the sweep.
    const std::vector<StampedPose> own = {own_pose(heading + 0.2, 0.9, 0.5, t - 400'000'000),
                                          own_pose(heading - 0.2, 0.35, 0.02, t + 30'000'000),
                                          own_pose(heading + 0.3, 0.7, 0.5, t + 300'000'000)};
    const BaseLinkResult r = base_link_pose(fix, own, BaseLinkConfig{kOffset, 0.5, 0.5});
    ASSERT_EQ(r.refusal, BaseLinkRefusal::kNone) << heading;
    EXPECT_NEAR(r.pose.position[0], 25.0, 1e-9);
    EXPECT_NEAR(r.pose.position[1], -4.0, 1e-9);
    EXPECT_DOUBLE_EQ(r.pose.position[2], 0.35);            // the nearest own pose's z ...
    EXPECT_DOUBLE_EQ(r.pose.covariance[2 * 6 + 2], 0.02);  // ... and its variance
    EXPECT_NEAR(std::remainder(yaw_of(r.pose.orientation) - heading, 2 * kPi), 0.0, 1e-9) << heading;
    EXPECT_NEAR(r.yaw_disagreement_rad, 0.2, 1e-9);
    EXPECT_EQ(r.pose.covariance[3 * 6 + 3], kUnknownVariance);
    EXPECT_EQ(r.pose.covariance[4 * 6 + 4], kUnknownVariance);
  }
}

TEST(BaseLinkPose, CovarianceIsTheSpreadOfBaseLinkUnderTheRsusCovariance) {
  const double heading = 2.6;
  const TimeNs t = 1'000'000'000;
  const StampedPose fix = rsu_fix(3.0, 7.0, heading, rsu_covariance(), t);
  const std::vector<StampedPose> own = {own_pose(heading, 0.3, 0.01, t)};
  const BaseLinkResult r = base_link_pose(fix, own, BaseLinkConfig{kOffset, 0.5, 0.5});
  ASSERT_EQ(r.refusal, BaseLinkRefusal::kNone);
  // Fixes drawn from the RSU's covariance about the true box pose, each moved to base_link by hand.
  const Eigen::Matrix3d chol = rsu_covariance().llt().matrixL();
  std::mt19937 rng(7);
  std::normal_distribution<double> n01;
  const double cx = fix.pose.position[0], cy = fix.pose.position[1];
  constexpr int kDraws = 40000;
  std::vector<Eigen::Vector3d> draws;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int k = 0; k < kDraws; ++k) {
    const Eigen::Vector3d e = chol * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
    const double yaw = heading + e.z();
    const Eigen::Vector3d b(cx + e.x() + std::cos(yaw) * kOffset.x() - std::sin(yaw) * kOffset.y(),
                            cy + e.y() + std::sin(yaw) * kOffset.x() + std::cos(yaw) * kOffset.y(), yaw);
    draws.push_back(b);
    mean += b / kDraws;
  }
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& b : draws)
    spread += (b - mean) * (b - mean).transpose() / (kDraws - 1);
  const std::array<int, 3> idx = {0, 1, 5};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double stated = r.pose.covariance[static_cast<std::size_t>(idx[i] * 6 + idx[j])];
      const double scale = std::sqrt(spread(i, i) * spread(j, j));
      EXPECT_NEAR(stated, spread(i, j), 0.03 * scale) << i << "," << j;
    }
  }
  // The yaw's share is really there: x's variance exceeds the RSU's centre variance.
  EXPECT_GT(r.pose.covariance[0], rsu_covariance()(0, 0) + 0.0015);
}

TEST(BaseLinkPose, RefusesAFixAcrossTheOwnHeadingOrWithoutARecentOwnPose) {
  const TimeNs t = 5'000'000'000;
  const StampedPose fix = rsu_fix(0.0, 0.0, 0.4, rsu_covariance(), t);
  const BaseLinkConfig config{kOffset, 0.5, 0.5};
  // The box 90 degrees off the heading (an off-by-90 fit): either branch is a guess.
  std::vector<StampedPose> own = {own_pose(0.4 + kPi / 2, 0.3, 0.01, t)};
  EXPECT_EQ(base_link_pose(fix, own, config).refusal, BaseLinkRefusal::kHeadingDisagreement);
  own = {own_pose(0.4 + 0.51, 0.3, 0.01, t)};
  EXPECT_EQ(base_link_pose(fix, own, config).refusal, BaseLinkRefusal::kHeadingDisagreement);
  own = {own_pose(0.4 + 0.49 + kPi, 0.3, 0.01, t)};  // driving the other way: fine
  EXPECT_EQ(base_link_pose(fix, own, config).refusal, BaseLinkRefusal::kNone);
  EXPECT_EQ(base_link_pose(fix, {}, config).refusal, BaseLinkRefusal::kNoOwnPose);
  own = {own_pose(0.4, 0.3, 0.01, t - 600'000'000), own_pose(0.4, 0.3, 0.01, t + 501'000'000)};
  EXPECT_EQ(base_link_pose(fix, own, config).refusal, BaseLinkRefusal::kNoOwnPose);
}

TEST(BaseLinkPose, RefusesMalformedFixes) {
  const TimeNs t = 5'000'000'000;
  const std::vector<StampedPose> own = {own_pose(0.0, 0.3, 0.01, t)};
  const BaseLinkConfig config{kOffset, 0.5, 0.5};
  StampedPose fix = rsu_fix(0.0, 0.0, 0.0, rsu_covariance(), t);
  ASSERT_EQ(base_link_pose(fix, own, config).refusal, BaseLinkRefusal::kNone);
  StampedPose bad = fix;
  bad.pose.position[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(base_link_pose(bad, own, config).refusal, BaseLinkRefusal::kMalformedFix);
  bad = fix;
  bad.pose.orientation = {0.0, 0.0, 0.5, 0.5};  // not a unit quaternion
  EXPECT_EQ(base_link_pose(bad, own, config).refusal, BaseLinkRefusal::kMalformedFix);
  bad = fix;
  bad.pose.covariance[0] = -0.01;  // not positive definite
  EXPECT_EQ(base_link_pose(bad, own, config).refusal, BaseLinkRefusal::kMalformedFix);
  bad = fix;
  bad.pose.covariance[1] = 0.5;  // not symmetric
  EXPECT_EQ(base_link_pose(bad, own, config).refusal, BaseLinkRefusal::kMalformedFix);
}

}  // namespace
}  // namespace rsu::ros
