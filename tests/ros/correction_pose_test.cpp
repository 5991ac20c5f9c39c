// SPDX-License-Identifier: Apache-2.0
// Correction -> PoseWithCovariance and ROS time: checked against what the numbers must mean (the
// quaternion rotates +x onto the heading; the 6x6 holds the 3x3 at x, y, yaw; times round-trip).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/symmetric_eigen.h"
#include "ros/correction_pose.h"
#include "ros/ros_time.h"

namespace rsu::ros {
namespace {

v2i::Correction correction(double yaw) {
  v2i::Correction c;
  c.pose = {12.5, -3.25, yaw};
  c.pose_covariance << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.0025;
  return c;
}

TEST(CorrectionPose, QuaternionTurnsXOntoTheHeading) {
  for (const double yaw : {0.0, 0.3, -1.2, std::numbers::pi / 2, 3.0, -3.1}) {
    const RosPoseWithCovariance p = to_ros_pose(correction(yaw));
    const Eigen::Quaterniond q(p.orientation[3], p.orientation[0], p.orientation[1], p.orientation[2]);
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
    const Eigen::Vector3d heading = q * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(heading.x(), std::cos(yaw), 1e-12);
    EXPECT_NEAR(heading.y(), std::sin(yaw), 1e-12);
    EXPECT_NEAR(heading.z(), 0.0, 1e-12);
    EXPECT_NEAR((q * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ()).norm(), 0.0,
                1e-12);  // no roll/pitch
    EXPECT_EQ(p.position[0], 12.5);
    EXPECT_EQ(p.position[1], -3.25);
    EXPECT_EQ(p.position[2], 0.0);
  }
}

TEST(CorrectionPose, CovarianceIsTheThreeByThreeAtXYYawAndUnknownElsewhere) {
  const v2i::Correction c = correction(0.7);
  const RosPoseWithCovariance p = to_ros_pose(c);
  const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> m(p.covariance.data());
  const int idx[3] = {0, 1, 5};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_EQ(m(idx[i], idx[j]), c.pose_covariance(i, j));
  for (int k = 2; k <= 4; ++k) {
    EXPECT_EQ(m(k, k), kUnknownVariance);
    for (int j = 0; j < 6; ++j)
      if (j != k) {
        EXPECT_EQ(m(k, j), 0.0);
        EXPECT_EQ(m(j, k), 0.0);
      }
  }
  EXPECT_TRUE(m.isApprox(m.transpose()));
  const SymmetricEigen6 eig(m);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
}

TEST(RosTime, RoundTripsAndKeepsNanosecInRange) {
  for (const TimeNs t :
       {TimeNs{0}, TimeNs{1}, TimeNs{-1}, TimeNs{1'700'000'000'999'999'999}, TimeNs{-5'500'000'000}}) {
    const RosTime r = to_ros_time(t);
    EXPECT_LT(r.nanosec, 1'000'000'000U);
    ASSERT_TRUE(from_ros_time(r).has_value());
    EXPECT_EQ(*from_ros_time(r), t);
  }
  EXPECT_EQ(to_ros_time(-1).sec, -1);
  EXPECT_EQ(to_ros_time(-1).nanosec, 999'999'999U);
  EXPECT_FALSE(from_ros_time({0, 1'000'000'000U}).has_value());
  // Beyond int32 seconds: saturated, never wrapped.
  EXPECT_EQ(to_ros_time(std::numeric_limits<TimeNs>::max()).sec, std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(to_ros_time(std::numeric_limits<TimeNs>::min()).sec, std::numeric_limits<std::int32_t>::min());
}

}  // namespace
}  // namespace rsu::ros
