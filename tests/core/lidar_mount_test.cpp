// SPDX-License-Identifier: Apache-2.0
// LidarMount::beam_azimuth (lidar_mount.h): the sensor's beam azimuth (clockwise from its +x, Velodyne's
// convention) at which a map point is seen, worked out here for level mounts facing the map's axes.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Core>

#include "common/angles.h"
#include "core/lidar_mount.h"

namespace rsu::core {
namespace lidar_mount_direct_test {

Pose3 level_mount(double yaw) {
  return Pose3{10.0, 20.0, 5.0, 0.0, 0.0, yaw};
}

// Facing east (+x): north (+y, the sensor's left) is 90 deg anticlockwise, -90 deg clockwise.
TEST(LidarMountAzimuth, ClockwiseFromTheSensorsForward) {
  const LidarMount m(level_mount(0.0));
  EXPECT_NEAR(m.beam_azimuth({20.0, 20.0}), 0.0, 1e-12);         // ahead
  EXPECT_NEAR(m.beam_azimuth({10.0, 30.0}), -kPi / 2.0, 1e-12);  // left
  EXPECT_NEAR(m.beam_azimuth({10.0, 10.0}), kPi / 2.0, 1e-12);   // right
  EXPECT_NEAR(m.beam_azimuth({20.0, 10.0}), kPi / 4.0, 1e-12);   // ahead right
  EXPECT_NEAR(m.beam_azimuth({20.0, 30.0}), -kPi / 4.0, 1e-12);
  // atan(1 / 2) to the right of ahead.
  EXPECT_NEAR(m.beam_azimuth({30.0, 10.0}), std::atan(0.5), 1e-12);
}

// Facing north: east is on the sensor's right (+90 deg), west on its left, south behind.
TEST(LidarMountAzimuth, FollowsTheMountsYaw) {
  const LidarMount m(level_mount(kPi / 2.0));
  EXPECT_NEAR(m.beam_azimuth({10.0, 40.0}), 0.0, 1e-12);
  EXPECT_NEAR(m.beam_azimuth({30.0, 20.0}), kPi / 2.0, 1e-12);
  EXPECT_NEAR(m.beam_azimuth({-10.0, 20.0}), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(std::abs(m.beam_azimuth({10.0, 0.0})), kPi, 1e-12);
  // Facing 30 deg: a point 30 deg + 20 deg anticlockwise of east is 20 deg to the left: -20 deg.
  const LidarMount turned(level_mount(deg_to_rad(30.0)));
  const double a = deg_to_rad(50.0);
  EXPECT_NEAR(turned.beam_azimuth({10.0 + 8.0 * std::cos(a), 20.0 + 8.0 * std::sin(a)}), deg_to_rad(-20.0),
              1e-12);
}

// The contract's range is (-pi, pi]: a point straight behind is +pi, not -pi (-atan2(+0, -x) = -pi
// unwrapped, for a mount at yaw 0, +-pi/2 or 0.3).
TEST(LidarMountAzimuth, StraightBehindIsPlusPi) {
  for (const double yaw : {0.0, kPi / 2.0, kPi, -kPi / 2.0, 0.3}) {
    const LidarMount m(level_mount(yaw));
    const Eigen::Vector2d behind(10.0 - 7.0 * std::cos(yaw), 20.0 - 7.0 * std::sin(yaw));
    const double a = m.beam_azimuth(behind);
    EXPECT_GT(a, -kPi) << "yaw " << yaw << ": " << a;
    EXPECT_LE(a, kPi) << "yaw " << yaw << ": " << a;
    EXPECT_NEAR(std::abs(a), kPi, 1e-9) << "yaw " << yaw;
  }
}

}  // namespace lidar_mount_direct_test
}  // namespace rsu::core
