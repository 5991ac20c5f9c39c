// SPDX-License-Identifier: Apache-2.0
#include "sim/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::sim {
namespace {

// Angle difference folded into [0, pi], computed here with atan2 (not the library's wrap_angle).
double angle_gap(double a, double b) {
  return std::abs(std::atan2(std::sin(a - b), std::cos(a - b)));
}

TEST(SimTrajectory, StaticPoseIsConstant) {
  const Trajectory t = StaticPose{{3.0, -4.0, 0.5}};
  for (const TimeNs time : {TimeNs{-5'000'000'000}, TimeNs{0}, TimeNs{123'456'789'000}}) {
    const Pose2 p = pose_at(t, time);
    EXPECT_DOUBLE_EQ(p.x, 3.0);
    EXPECT_DOUBLE_EQ(p.y, -4.0);
    EXPECT_DOUBLE_EQ(p.yaw, 0.5);
  }
}

TEST(SimTrajectory, SpinAngleAtTime) {
  Spin s;
  s.x = 10.0;
  s.y = 2.0;
  s.yaw0 = 0.3;
  s.rate_rad_s = 20.0 * kPi / 180.0;  // the pilot experiment: 20 deg/s
  s.t0 = 1'000'000'000;
  const Trajectory t = s;
  for (const double seconds : {0.0, 0.1, 2.5, 17.3, 100.0, -3.0}) {
    const TimeNs time = s.t0 + static_cast<TimeNs>(std::llround(seconds * 1e9));
    const Pose2 p = pose_at(t, time);
    EXPECT_DOUBLE_EQ(p.x, 10.0);
    EXPECT_DOUBLE_EQ(p.y, 2.0);
    EXPECT_LT(angle_gap(p.yaw, 0.3 + s.rate_rad_s * seconds), 1e-9) << seconds;
    EXPECT_GT(p.yaw, -kPi);
    EXPECT_LE(p.yaw, kPi);
  }
  // One full turn takes 18 s at 20 deg/s.
  EXPECT_LT(angle_gap(pose_at(t, s.t0 + 18'000'000'000).yaw, 0.3), 1e-9);
  EXPECT_DOUBLE_EQ(velocity_at(t, 0).yaw_rate, s.rate_rad_s);
}

TEST(SimTrajectory, WaypointsInterpolateLinearlyAndHoldAtTheEnds) {
  Waypoints w;
  w.points = {{0, {0.0, 0.0, 0.0}}, {10'000'000'000, {10.0, 5.0, 0.5}}, {12'000'000'000, {10.0, 9.0, 0.5}}};
  const Trajectory t = w;
  Pose2 p = pose_at(t, 2'500'000'000);
  EXPECT_NEAR(p.x, 2.5, 1e-12);
  EXPECT_NEAR(p.y, 1.25, 1e-12);
  EXPECT_NEAR(p.yaw, 0.125, 1e-12);
  p = pose_at(t, 11'000'000'000);
  EXPECT_NEAR(p.x, 10.0, 1e-12);
  EXPECT_NEAR(p.y, 7.0, 1e-12);
  p = pose_at(t, -1'000'000'000);  // before the first point
  EXPECT_DOUBLE_EQ(p.x, 0.0);
  EXPECT_DOUBLE_EQ(p.y, 0.0);
  p = pose_at(t, 99'000'000'000);  // after the last
  EXPECT_DOUBLE_EQ(p.x, 10.0);
  EXPECT_DOUBLE_EQ(p.y, 9.0);

  const Velocity2 v = velocity_at(t, 3'000'000'000);
  EXPECT_NEAR(v.vx, 1.0, 1e-12);
  EXPECT_NEAR(v.vy, 0.5, 1e-12);
  EXPECT_NEAR(v.yaw_rate, 0.05, 1e-12);
  const Velocity2 held = velocity_at(t, 13'000'000'000);
  EXPECT_EQ(held.vx, 0.0);
  EXPECT_EQ(held.vy, 0.0);
}

TEST(SimTrajectory, WaypointYawTakesTheShortWayRound) {
  Waypoints w;
  const double from = 170.0 * kPi / 180.0;
  const double to = -170.0 * kPi / 180.0;
  w.points = {{0, {0, 0, from}}, {2'000'000'000, {0, 0, to}}};
  const Trajectory t = w;
  // Through 180 deg (20 deg of turn), not back through 0 (340 deg).
  EXPECT_LT(angle_gap(pose_at(t, 1'000'000'000).yaw, kPi), 1e-12);
  EXPECT_LT(angle_gap(pose_at(t, 500'000'000).yaw, 175.0 * kPi / 180.0), 1e-12);
  EXPECT_LT(angle_gap(pose_at(t, 1'500'000'000).yaw, -175.0 * kPi / 180.0), 1e-12);
  EXPECT_NEAR(velocity_at(t, 1).yaw_rate, 10.0 * kPi / 180.0, 1e-12);
}

TEST(SimTrajectory, EqualTimesMakeAJump) {
  Waypoints w;
  w.points = {
      {0, {0, 0, 0}}, {1'000'000'000, {1, 0, 0}}, {1'000'000'000, {5, 0, 0}}, {2'000'000'000, {6, 0, 0}}};
  const Trajectory t = w;
  EXPECT_NEAR(pose_at(t, 999'999'999).x, 1.0, 1e-6);
  EXPECT_DOUBLE_EQ(pose_at(t, 1'000'000'000).x, 5.0);
  EXPECT_NEAR(pose_at(t, 1'500'000'000).x, 5.5, 1e-12);
}

TEST(SimTrajectory, PathVerticesIncludeInteriorWaypoints) {
  Waypoints w;
  w.points = {{0, {0, 0, 0}}, {1'000'000'000, {4, 0, 0}}, {2'000'000'000, {4, 4, 0}}};
  const auto path = path_vertices(w, 500'000'000, 1'500'000'000);
  ASSERT_EQ(path.size(), 3U);
  EXPECT_NEAR(path[0].x(), 2.0, 1e-12);
  EXPECT_NEAR(path[1].x(), 4.0, 1e-12);
  EXPECT_NEAR(path[1].y(), 0.0, 1e-12);
  EXPECT_NEAR(path[2].y(), 2.0, 1e-12);
}

TEST(SimTrajectory, InvalidTrajectoriesThrow) {
  EXPECT_THROW(pose_at(Waypoints{}, 0), std::invalid_argument);
  EXPECT_THROW(validate_trajectory(Waypoints{}), std::invalid_argument);
  Waypoints backwards;
  backwards.points = {{10, {0, 0, 0}}, {5, {1, 0, 0}}};
  EXPECT_THROW(validate_trajectory(backwards), std::invalid_argument);
  Spin s;
  s.rate_rad_s = std::numeric_limits<double>::infinity();
  EXPECT_THROW(validate_trajectory(s), std::invalid_argument);
  EXPECT_THROW(validate_trajectory(StaticPose{{std::numeric_limits<double>::quiet_NaN(), 0, 0}}),
               std::invalid_argument);
  EXPECT_NO_THROW(validate_trajectory(Spin{}));
}

// Smooth waypoints: through every point at its time, yaw along the direction of motion, and velocity
// continuous across the points (the ground truth is computed here by finite differences).
TEST(SimTrajectory, SmoothWaypointsFollowTheirTangent) {
  Waypoints w;
  w.smooth = true;
  w.points = {{0, {-60.0, -5.25, 0.0}},
              {from_seconds(4.5), {-10.0, -5.25, 0.0}},
              {from_seconds(5.75), {3.9, -3.5, 0.0}},
              {from_seconds(7.0), {17.8, -1.75, 0.0}},
              {from_seconds(10.8), {60.0, -1.75, 0.0}}};
  const Trajectory tr = w;
  for (const TimedPose& p : w.points) {
    const Pose2 at = pose_at(tr, p.t);
    EXPECT_NEAR(at.x, p.pose.x, 1e-9);
    EXPECT_NEAR(at.y, p.pose.y, 1e-9);
  }
  const TimeNs h = 100'000;  // 0.1 ms
  for (TimeNs t = from_seconds(0.3); t < from_seconds(10.5); t += from_seconds(0.173)) {
    const Pose2 a = pose_at(tr, t - h), b = pose_at(tr, t + h), c = pose_at(tr, t);
    const double vx = (b.x - a.x) / to_seconds(2 * h), vy = (b.y - a.y) / to_seconds(2 * h);
    EXPECT_NEAR(c.yaw, std::atan2(vy, vx), 1e-6) << "t = " << to_seconds(t);
    const Velocity2 v = velocity_at(tr, t);
    EXPECT_NEAR(v.vx, vx, 1e-4);
    EXPECT_NEAR(v.vy, vy, 1e-4);
    EXPECT_NEAR(v.yaw_rate, wrap_angle(b.yaw - a.yaw) / to_seconds(2 * h), 2e-3);
  }
  // No jump of the velocity at an interior point.
  const TimeNs knot = w.points[2].t;
  const Velocity2 before = velocity_at(tr, knot - h), after = velocity_at(tr, knot + h);
  EXPECT_NEAR(before.vx, after.vx, 1e-2);
  EXPECT_NEAR(before.vy, after.vy, 1e-2);
  // The linear version of the same points crabs: its yaw (0) differs from its direction of motion.
  Waypoints linear = w;
  linear.smooth = false;
  const Velocity2 crab = velocity_at(linear, from_seconds(5.0));
  EXPECT_GT(std::abs(std::atan2(crab.vy, crab.vx)), deg_to_rad(5.0));
}

}  // namespace
}  // namespace rsu::sim
