// SPDX-License-Identifier: Apache-2.0
// GrownFootprint's shares of a detection's points (grown_footprint.h): inside the footprint grown by its
// sigmas, tightly inside (the minimum margin and one centre sigma), inside the lane (grown along, tight
// across), with the margins worked out here from the constructor's contract.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "core/grown_footprint.h"

namespace rsu::core {
namespace grown_footprint_direct_test {

// A 4 x 2 m car at (100, 50) heading `yaw`, centre sigmas 0.1 and 0.05 m, yaw sigma 0.1 rad. With the
// defaults (2.5 sigmas, margins in [0.4, 2.0] m, half of the points), the margin is
//   2.5 (0.1 + 0.1 x hypot(4, 2) / 2) = 2.5 (0.1 + 0.223607) = 0.809017 m
// (half extents 2.809017 x 1.809017), the tight one 0.4 + 0.1 = 0.5 m (2.5 x 1.5), the lane's
// 2.809017 x 1.5.
tracking::VehicleHypothesis car_at(double yaw) {
  tracking::VehicleHypothesis h;
  h.centre = Eigen::Vector2d(100.0, 50.0);
  h.yaw = yaw;
  h.covariance = Eigen::Vector3d(0.01, 0.0025, 0.01).asDiagonal();
  h.size.length_m = 4.0;
  h.size.width_m = 2.0;
  h.size.height_m = 1.5;
  return h;
}

// A detection of points given in the car's frame (along, across) at heading `yaw`.
perception::Detection detection_at(double yaw, const std::vector<Eigen::Vector2d>& local) {
  perception::Detection d;
  const double c = std::cos(yaw), s = std::sin(yaw);
  for (const Eigen::Vector2d& q : local)
    d.points.emplace_back(100.0 + c * q.x() - s * q.y(), 50.0 + s * q.x() + c * q.y(), 0.8);
  return d;
}

TEST(GrownFootprintShares, PointsCountByTheMarginOfEachFootprint) {
  for (const double yaw : {0.0, 0.7, kPi / 2.0, -2.5}) {
    const GrownFootprint f(car_at(yaw), GatheringConfig{});
    // Beyond the tight length (2.5) but within the grown one (2.809): in the lane, not tight.
    const auto ahead = detection_at(yaw, {{0.0, 0.0}, {2.7, 0.0}, {2.7, 0.5}});
    EXPECT_NEAR(f.inside_fraction(ahead), 1.0, 1e-12) << yaw;
    EXPECT_FALSE(f.tightly_inside(ahead)) << yaw;  // 1 of 3
    EXPECT_TRUE(f.inside_lane(ahead)) << yaw;      // 3 of 3
    // Beside it, beyond the tight width (1.5) but within the grown one (1.809): neither.
    const auto beside = detection_at(yaw, {{0.0, 0.0}, {0.0, 1.7}, {1.0, -1.7}});
    EXPECT_NEAR(f.inside_fraction(beside), 1.0, 1e-12) << yaw;
    EXPECT_FALSE(f.tightly_inside(beside)) << yaw;
    EXPECT_FALSE(f.inside_lane(beside)) << yaw;
    // Beyond everything: (3.0, 0) and (0, 1.9).
    const auto partly = detection_at(yaw, {{0.0, 0.0}, {1.0, 1.0}, {3.0, 0.0}, {0.0, 1.9}});
    EXPECT_NEAR(f.inside_fraction(partly), 0.5, 1e-12) << yaw;
    EXPECT_TRUE(f.tightly_inside(partly)) << yaw;  // 2 of 4 = the minimum, which counts
    EXPECT_TRUE(f.inside_lane(partly)) << yaw;
  }
}

// At yaw 0 the edges are exact in floating point: a point on the tight edge (2.5 along) is inside it.
TEST(GrownFootprintShares, PointsOnTheEdgeAreInside) {
  const GrownFootprint f(car_at(0.0), GatheringConfig{});
  EXPECT_TRUE(f.tightly_inside(detection_at(0.0, {{2.5, 0.0}, {-2.5, 1.5}})));
  EXPECT_FALSE(f.tightly_inside(detection_at(0.0, {{2.5001, 0.0}, {-2.5, 1.5001}})));
}

// A point ahead of the car turned by 90 deg lies beside it: the footprint turns with the yaw.
TEST(GrownFootprintShares, FootprintTurnsWithTheVehicle) {
  const GrownFootprint north(car_at(kPi / 2.0), GatheringConfig{});
  // (102.7, 50) is 2.7 m east of the centre: across a car heading north, beyond its grown width.
  perception::Detection east;
  east.points = {Eigen::Vector3d(102.7, 50.0, 0.5)};
  EXPECT_EQ(north.inside_fraction(east), 0.0);
  perception::Detection ahead;
  ahead.points = {Eigen::Vector3d(100.0, 52.7, 0.5)};
  EXPECT_EQ(north.inside_fraction(ahead), 1.0);
  EXPECT_TRUE(north.inside_lane(ahead));
  EXPECT_FALSE(north.tightly_inside(ahead));
}

// A lost vehicle (infinite covariance) is grown by the maximum margin, 2 m: 4 x 3 m half extents.
TEST(GrownFootprintShares, LostVehicleIsGrownByTheMaximumMargin) {
  tracking::VehicleHypothesis h = car_at(0.0);
  h.covariance = Eigen::Matrix3d::Identity() * std::numeric_limits<double>::infinity();
  const GrownFootprint f(h, GatheringConfig{});
  EXPECT_EQ(f.inside_fraction(detection_at(0.0, {{3.9, 0.0}, {0.0, 2.9}, {4.1, 0.0}, {0.0, 3.1}})), 0.5);
}

TEST(GrownFootprintShares, EmptyDetectionIsNeitherTightlyInsideNorInTheLane) {
  const GrownFootprint f(car_at(0.3), GatheringConfig{});
  const perception::Detection none;
  EXPECT_EQ(f.inside_fraction(none), 0.0);  // not 0 / 0
  EXPECT_FALSE(f.tightly_inside(none));
  EXPECT_FALSE(f.inside_lane(none));
}

}  // namespace grown_footprint_direct_test
}  // namespace rsu::core
