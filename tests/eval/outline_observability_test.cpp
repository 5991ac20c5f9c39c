// SPDX-License-Identifier: Apache-2.0
// The pilot's oracle of whether a frame's points show the footprint's place (outline_observability.h), on
// points placed by hand on a 4 x 2 m box turned 30 deg and moved off the origin.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "eval/pilot/outline_observability.h"

namespace rsu::eval {
namespace outline_observability_test {
namespace {

const Pose2 kTruth{10.0, -3.0, 0.5235987755982988};  // 30 deg
constexpr double kLength = 4.0;
constexpr double kWidth = 2.0;

// A point at (u along the length, v across) in the box's frame, at height z.
Eigen::Vector3d at(double u, double v, double z = 0.5) {
  const double c = std::cos(kTruth.yaw), s = std::sin(kTruth.yaw);
  return {kTruth.x + c * u - s * v, kTruth.y + s * u + c * v, z};
}

// A run of n points along the length at v, from u0 to u1.
void add_run(std::vector<Eigen::Vector3d>& points, double u0, double u1, double v, int n) {
  for (int i = 0; i < n; ++i)
    points.push_back(at(u0 + (u1 - u0) * i / (n - 1), v));
}

TEST(OutlineObservability, ASideAndAnEndSeenPinBothAxes) {
  std::vector<Eigen::Vector3d> points;
  add_run(points, -1.5, 1.5, -0.98, 20);  // the near side, 2 cm inside the outline
  for (int i = 0; i < 5; ++i)
    points.push_back(at(1.97, -0.8 + 0.3 * i));  // the front, 3 cm inside
  const OutlineObservability o = observe_outline(points, kTruth, kLength, kWidth);
  EXPECT_TRUE(o.length_pinned);
  EXPECT_TRUE(o.width_pinned);
  EXPECT_TRUE(o.seen());
}

TEST(OutlineObservability, ARoofInsideTheOutlinePinsNeither) {
  // A glasshouse 0.12 m inside the sides, 1.2 m behind the front and 0.3 m ahead of the back.
  std::vector<Eigen::Vector3d> points;
  for (int row = 0; row < 6; ++row)
    add_run(points, -1.7, 0.8, -0.88 + 0.35 * row, 25);
  const OutlineObservability o = observe_outline(points, kTruth, kLength, kWidth);
  EXPECT_FALSE(o.length_pinned);
  EXPECT_FALSE(o.width_pinned);
  EXPECT_FALSE(o.seen());
}

TEST(OutlineObservability, TwoPointsAtAnEdgeAreNotEnoughButThreeAre) {
  std::vector<Eigen::Vector3d> points;
  add_run(points, -1.0, 1.0, 0.0, 10);  // along the middle: neither side
  points.push_back(at(-1.99, 0.1));
  points.push_back(at(-1.98, -0.1));
  EXPECT_FALSE(observe_outline(points, kTruth, kLength, kWidth).length_pinned);
  points.push_back(at(-1.96, 0.0));
  EXPECT_TRUE(observe_outline(points, kTruth, kLength, kWidth).length_pinned);
  EXPECT_FALSE(observe_outline(points, kTruth, kLength, kWidth).width_pinned);
}

TEST(OutlineObservability, ContainmentPinsAnAxisThePointsSpan) {
  // A bus-like roof spanning the whole length to within 4 cm at each end, one point at each: no end has
  // three points, but containment leaves the centre within 0.04 m.
  std::vector<Eigen::Vector3d> points;
  add_run(points, -1.96, 1.96, 0.0, 2);
  EXPECT_TRUE(observe_outline(points, kTruth, kLength, kWidth).length_pinned);
  // Spanning 0.12 m short of the length, it does not.
  points.clear();
  add_run(points, -1.94, 1.94, 0.0, 2);
  EXPECT_FALSE(observe_outline(points, kTruth, kLength, kWidth).length_pinned);
}

TEST(OutlineObservability, NoPointsOrNonFiniteOnesPinNothing) {
  EXPECT_FALSE(observe_outline({}, kTruth, kLength, kWidth).seen());
  const double nan = std::nan("");
  const std::vector<Eigen::Vector3d> points(5, Eigen::Vector3d(nan, 0.0, 0.0));
  const OutlineObservability o = observe_outline(points, kTruth, kLength, kWidth);
  EXPECT_FALSE(o.length_pinned);
  EXPECT_FALSE(o.width_pinned);
}

}  // namespace
}  // namespace outline_observability_test
}  // namespace rsu::eval
