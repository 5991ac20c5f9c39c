// SPDX-License-Identifier: Apache-2.0
// SweepOccluders (sweep_occluders.h): which other objects' points may hide a released vehicle.
#include "core/sweep_occluders.h"
#include "lidar/point_eigen.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/angles.h"

namespace rsu::core {
namespace {

// A detection of points spaced 0.1 m along y at x = `x`, from y0 to y1, swept at `t`.
perception::Detection detection_at(double x, double y0, double y1, TimeNs t) {
  perception::Detection d;
  for (double y = y0; y <= y1 + 1e-9; y += 0.1)
    d.points.emplace_back(x, y, 0.8);
  d.sweep_time_ns = t;
  return d;
}

// What may hide a vehicle (sweep_occluders.h): another object of the same sweep nearer the LiDAR in the
// vehicle's direction; not the vehicle's own points, not objects beside it or behind it, not another
// rotation's.
TEST(SweepOccluders, OtherObjectsNearerInTheVehiclesDirection) {
  constexpr TimeNs kRotation = 100'000'000;
  SweepOccluders occluders(Eigen::Vector2d::Zero(), kRotation);
  const TimeNs t = 5 * kRotation;
  const perception::Detection vehicle = detection_at(20.0, -1.0, 2.0, t);
  const perception::Detection in_front = detection_at(10.0, 0.5, 1.0, t + 1'000'000);
  const perception::Detection beside = detection_at(10.0, 6.0, 7.0, t);  // 31 deg off its direction
  const perception::Detection behind = detection_at(30.0, 0.0, 1.0, t);
  const perception::Detection last_rotation = detection_at(12.0, -0.5, 0.0, t - kRotation + 2'000'000);
  occluders.add(std::vector<perception::Detection>{last_rotation});
  occluders.add(std::vector<perception::Detection>{vehicle, in_front, beside, behind});
  ASSERT_EQ(occluders.detections_kept(), 5U);

  HeldVehicle held;
  held.points = vehicle.points;
  held.first_time = t;
  const std::vector<Eigen::Vector2d> got = occluders.of(held);
  ASSERT_EQ(got.size(), in_front.points.size());
  for (const Eigen::Vector2d& xy : got)
    EXPECT_DOUBLE_EQ(xy.x(), 10.0);

  // A rotation later, the first batches are forgotten.
  occluders.add(std::vector<perception::Detection>{detection_at(5.0, 0.0, 0.2, t + 2 * kRotation)});
  EXPECT_EQ(occluders.detections_kept(), 1U);
}

// The clusters still open that a released one went ahead of hide it too; but when a vehicle's fix is
// prepared before its own cluster is released (prepared_fixes.h), that cluster is among them, and it is
// the vehicle, not what hides it (issue 16: every such prepared fix differed from its release's, which had
// no such occluder, and was computed twice).
TEST(SweepOccluders, OpenClustersButTheVehiclesOwn) {
  SweepOccluders occluders(Eigen::Vector2d::Zero(), 100'000'000);
  const auto cluster_at = [](double x, double y0, double y1) {
    std::vector<lidar::LidarPoint> points;
    for (const Eigen::Vector3d& p : detection_at(x, y0, y1, 0).points)
      points.push_back({.x = static_cast<float>(p.x()), .y = static_cast<float>(p.y()), .z = 0.8f});
    return points;
  };
  const std::vector<lidar::LidarPoint> own = cluster_at(20.0, -1.0, 2.0);
  const std::vector<lidar::LidarPoint> in_front = cluster_at(10.0, 0.5, 1.0);
  const std::vector<std::vector<lidar::LidarPoint>> open = {own, in_front};
  occluders.set_unfinished(open);
  HeldVehicle held;
  for (const lidar::LidarPoint& p : own)  // as perception::Detection holds them
    held.points.push_back(lidar::position_of(p));
  const std::vector<Eigen::Vector2d> got = occluders.of(held);
  ASSERT_EQ(got.size(), in_front.size());
  for (const Eigen::Vector2d& xy : got)
    EXPECT_NEAR(xy.x(), 10.0, 1e-6);
  // Another vehicle behind both is hidden by both.
  HeldVehicle behind;
  behind.points = detection_at(30.0, 0.0, 1.5, 0).points;
  EXPECT_GT(occluders.of(behind).size(), in_front.size());
}

// The static scene's objects (a background rotation's returns above the road) hide vehicles too, kept
// once per 0.1 m cell; the road's returns do not.
TEST(SweepOccluders, StaticObjectsAboveTheRoad) {
  SweepOccluders occluders(Eigen::Vector2d::Zero(), 100'000'000);
  std::vector<lidar::LidarPoint> background;
  for (int pass = 0; pass < 2; ++pass) {  // two rotations of the same scene
    for (double z = 0.5; z <= 3.0; z += 0.5)
      background.push_back({.x = 10.0f, .y = 0.5f, .z = static_cast<float>(z)});  // a post in front
    background.push_back({.x = 10.0f, .y = -0.5f, .z = 0.05f});                   // the road
    background.push_back({.x = 30.0f, .y = 0.0f, .z = 1.0f});                     // a wall behind
    background.push_back({.x = -10.0f, .y = 0.0f, .z = 1.0f});                    // behind the LiDAR
  }
  occluders.add_static(background, 0.2);
  EXPECT_EQ(occluders.static_points(), 3U);
  HeldVehicle held;
  held.points = detection_at(20.0, -1.0, 2.0, 0).points;
  const std::vector<Eigen::Vector2d> got = occluders.of(held);
  ASSERT_EQ(got.size(), 1U);
  EXPECT_NEAR(got[0].x(), 10.0, 1e-6);
  EXPECT_NEAR(got[0].y(), 0.5, 1e-6);
  // A reload that keeps the background keeps them.
  SweepOccluders reloaded(Eigen::Vector2d::Zero(), 100'000'000);
  reloaded.take_static(std::move(occluders));
  EXPECT_EQ(reloaded.static_points(), 3U);
  EXPECT_EQ(reloaded.of(held).size(), 1U);
}

// The rule of sweep_occluders.h written plainly, an arctangent per point: the other detection's points
// nearer the LiDAR than the vehicle's farthest, whose azimuth about the vehicle's first point lies within
// the vehicle's span about it widened by 5 degrees.
std::vector<Eigen::Vector2d> nearer_within_span(const Eigen::Vector2d& lidar,
                                                const std::vector<Eigen::Vector3d>& vehicle,
                                                const std::vector<Eigen::Vector3d>& other) {
  const Eigen::Vector2d ref = vehicle.front().head<2>() - lidar;
  const auto about_ref = [&](const Eigen::Vector2d& r) {
    return wrap_angle(std::atan2(r.y(), r.x()) - std::atan2(ref.y(), ref.x()));
  };
  double lo = 0.0, hi = 0.0, farthest = 0.0;
  for (const Eigen::Vector3d& p : vehicle) {
    const Eigen::Vector2d r = p.head<2>() - lidar;
    lo = std::min(lo, about_ref(r));
    hi = std::max(hi, about_ref(r));
    farthest = std::max(farthest, r.norm());
  }
  std::vector<Eigen::Vector2d> out;
  for (const Eigen::Vector3d& p : other) {
    const Eigen::Vector2d r = p.head<2>() - lidar;
    const double a = about_ref(r);
    if (r.norm() < farthest && a >= lo - deg_to_rad(5.0) && a <= hi + deg_to_rad(5.0))
      out.push_back(p.head<2>());
  }
  return out;
}

// The candidates are decided by pseudo-angles, and by their angle only near an edge of the span (issue
// 16: an arctangent per point was on the correction's path): the points taken are exactly the plain
// rule's, for objects all around the LiDAR, points within 1e-13 to 1e-7 rad of the span's edges and
// nearly opposite the vehicle, and a vehicle whose widened span covers every direction.
TEST(SweepOccluders, TakesExactlyThePointsTheirAnglesWould) {
  constexpr TimeNs kRotation = 100'000'000;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int taken = 0, near_an_edge = 0;
  for (int scene = 0; scene < 60; ++scene) {
    const Eigen::Vector2d lidar(10.0 * unit(rng) - 5.0, 10.0 * unit(rng) - 5.0);
    // The vehicle: a box of points 8-30 m out in any direction; every tenth scene one around the LiDAR.
    const bool around = scene % 10 == 9;
    const double bearing = 2.0 * kPi * unit(rng), range = 8.0 + 22.0 * unit(rng);
    perception::Detection vehicle;
    vehicle.sweep_time_ns = 5 * kRotation;
    for (int i = 0; i < 200; ++i) {
      const double b = around ? 2.0 * kPi * unit(rng) : bearing + 0.15 * (unit(rng) - 0.5);
      const double r = around ? 3.0 + 2.0 * unit(rng) : range + 4.0 * unit(rng);
      vehicle.points.emplace_back(lidar.x() + r * std::cos(b), lidar.y() + r * std::sin(b), 0.8);
    }
    // Another object of the same sweep: points in every direction, and on the span's edges.
    perception::Detection other;
    other.sweep_time_ns = vehicle.sweep_time_ns;
    for (int i = 0; i < 2000; ++i) {
      const double b = 2.0 * kPi * unit(rng), r = 1.0 + 40.0 * unit(rng);
      other.points.emplace_back(lidar.x() + r * std::cos(b), lidar.y() + r * std::sin(b), 0.5);
    }
    const Eigen::Vector2d ref = vehicle.points.front().head<2>() - lidar;
    double lo = 0.0, hi = 0.0;
    for (const Eigen::Vector3d& p : vehicle.points) {
      const Eigen::Vector2d r = p.head<2>() - lidar;
      const double a = wrap_angle(std::atan2(r.y(), r.x()) - std::atan2(ref.y(), ref.x()));
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    for (const double edge : {lo - deg_to_rad(5.0), hi + deg_to_rad(5.0), kPi}) {
      for (const double off : {0.0, 1e-13, -1e-13, 1e-11, -1e-11, 1e-10, -1e-10, 1e-9, -1e-9, 1e-7, -1e-7}) {
        const double b = std::atan2(ref.y(), ref.x()) + edge + off, r = 2.0 + 5.0 * unit(rng);
        other.points.emplace_back(lidar.x() + r * std::cos(b), lidar.y() + r * std::sin(b), 0.5);
        ++near_an_edge;
      }
    }
    SweepOccluders occluders(lidar, kRotation);
    occluders.add(std::vector<perception::Detection>{vehicle, other});
    HeldVehicle held;
    held.points = vehicle.points;
    held.first_time = vehicle.sweep_time_ns;
    const std::vector<Eigen::Vector2d> got = occluders.of(held);
    const std::vector<Eigen::Vector2d> want = nearer_within_span(lidar, vehicle.points, other.points);
    ASSERT_EQ(got.size(), want.size()) << "scene " << scene;
    for (std::size_t i = 0; i < got.size(); ++i)
      ASSERT_EQ(got[i], want[i]) << "scene " << scene << ", point " << i;
    taken += static_cast<int>(got.size());
  }
  EXPECT_GT(taken, 3000);  // the scenes do exercise the rule
  EXPECT_EQ(near_an_edge, 60 * 33);
}

}  // namespace
}  // namespace rsu::core
