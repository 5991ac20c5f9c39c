// SPDX-License-Identifier: Apache-2.0
#include "tracking/vehicle_hypothesis.h"

#include <gtest/gtest.h>

#include <cmath>

#include "../v2i/test_announcement.h"
#include "common/angles.h"

namespace rsu::tracking {
namespace {

using v2i::VehicleAnnouncement;
namespace testing = v2i::testing;

constexpr TimeNs kT0 = 50 * kNsPerSecond;

VehicleAnnouncement moving(double yaw, double speed, double yaw_rate) {
  VehicleAnnouncement a = testing::make_announcement(9, 1, kT0);
  a.pose = {10.0, 20.0, yaw};
  a.speed_mps = speed;
  a.yaw_rate_rps = yaw_rate;
  return a;
}

TEST(VehicleHypothesis, StraightDriveAndReferenceOffset) {
  VehicleAnnouncement a = moving(0.0, 10.0, 0.0);
  a.reference_offset = {-1.35, 0.0};  // rear axle 1.35 m behind the box centre
  const VehicleHypothesis h = predict_hypothesis(a, kT0 + 100 * kNsPerMs);
  EXPECT_NEAR(h.centre.x(), 10.0 + 1.0 + 1.35, 1e-9);
  EXPECT_NEAR(h.centre.y(), 20.0, 1e-9);
  EXPECT_NEAR(h.yaw, 0.0, 1e-12);
  EXPECT_EQ(h.vehicle_id, 9U);
  EXPECT_EQ(h.size.length_m, a.size.length_m);

  // Backwards in time works the same way.
  const VehicleHypothesis back = predict_hypothesis(a, kT0 - 100 * kNsPerMs);
  EXPECT_NEAR(back.centre.x(), 10.0 - 1.0 + 1.35, 1e-9);
}

TEST(VehicleHypothesis, FollowsTheTurningCircle) {
  VehicleAnnouncement a = moving(0.3, 10.0, 0.5);
  a.reference_offset = {0.0, 0.0};
  const double t = 1.0;
  const VehicleHypothesis h = predict_hypothesis(a, kT0 + kNsPerSecond);
  // Independent geometry: a circle of radius v / w about the turn centre left of the vehicle.
  const double radius = 10.0 / 0.5;
  const double cx = 10.0 - radius * std::sin(0.3);
  const double cy = 20.0 + radius * std::cos(0.3);
  EXPECT_NEAR(h.centre.x(), cx + radius * std::sin(0.3 + 0.5 * t), 1e-9);
  EXPECT_NEAR(h.centre.y(), cy - radius * std::cos(0.3 + 0.5 * t), 1e-9);
  EXPECT_NEAR(h.yaw, 0.8, 1e-12);
}

TEST(VehicleHypothesis, UnknownSpeedStretchesTheGateAlongTheHeading) {
  VehicleAnnouncement a = moving(kPi / 2.0, 0.0, 0.0);  // facing north
  a.speed_mps.reset();
  a.pose_covariance = Eigen::Matrix3d::Identity() * 0.01;
  const VehicleHypothesis unknown = predict_hypothesis(a, kT0 + 500 * kNsPerMs);
  EXPECT_GT(unknown.covariance(1, 1), 10.0 * unknown.covariance(0, 0));
  // 8 m/s sigma over 0.5 s: about 4 m along-track.
  EXPECT_GT(std::sqrt(unknown.covariance(1, 1)), 3.5);
  EXPECT_LT(unknown.covariance(0, 0), 0.05);

  a.speed_mps = 5.0;
  const VehicleHypothesis known = predict_hypothesis(a, kT0 + 500 * kNsPerMs);
  EXPECT_LT(known.covariance(1, 1), 0.2 * unknown.covariance(1, 1));
  // With zero elapsed time and the box centre as reference point, the announced covariance comes
  // through unchanged...
  a.reference_offset = {0.0, 0.0};
  const VehicleHypothesis now = predict_hypothesis(a, kT0);
  EXPECT_NEAR((now.covariance - a.pose_covariance).norm(), 0.0, 1e-12);
  // ...while a rear-axle reference point 1.35 m behind the centre adds the lever arm: yaw error swings
  // the centre sideways (x, for a car facing north) by 1.35 m * yaw error.
  a.reference_offset = {-1.35, 0.0};
  const VehicleHypothesis lever = predict_hypothesis(a, kT0);
  EXPECT_NEAR(lever.covariance(0, 0), 0.01 + 1.35 * 1.35 * 0.01, 1e-12);
  EXPECT_NEAR(lever.covariance(1, 1), 0.01, 1e-12);
}

}  // namespace
}  // namespace rsu::tracking
