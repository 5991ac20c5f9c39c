// SPDX-License-Identifier: Apache-2.0
// The whole per-frame pipeline on synthetic 3D frames whose vehicles the test placed.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "common/angles.h"
#include "perception/pipeline.h"
#include "perception/sweep_clusterer.h"
#include "synthetic_scene.h"

namespace rsu::perception {
namespace {

using test::TrueBox;

struct BusyStreet {
  test::Scene3d empty;
  test::Scene3d busy;
  test::Lidar3d lidar = test::small_lidar(16);
  // Both vehicles show an L. (Seen end-on from 2 m, a box's roof returns land metres behind its front
  // face, beyond the clustering tolerance, and form a cluster of their own; the Algorithm 1 test below
  // has that case.)
  BusyStreet() { busy.vehicles = {{{12.0, 3.0}, 1.0, 4.89, 1.92}, {{-6.0, -15.0}, 0.3, 4.5, 1.8}}; }
};

const TrueBox* nearest_vehicle(const test::Scene3d& scene, const Eigen::Vector2d& p) {
  const TrueBox* best = nullptr;
  for (const auto& v : scene.vehicles) {
    if (best == nullptr || (v.centre - p).norm() < (best->centre - p).norm())
      best = &v;
  }
  return best;
}

// The firing time of each point of `frame`, by its coordinates (the objects keep only those).
std::map<std::array<double, 3>, TimeNs> firing_times(const std::vector<lidar::LidarPoint>& frame) {
  std::map<std::array<double, 3>, TimeNs> out;
  for (const lidar::LidarPoint& p : frame)
    out[{static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)}] = p.time_ns;
  return out;
}

void expect_finds_and_corrects_vehicles(const PerceptionPipeline& pipeline, const test::Scene3d& scene,
                                        const std::vector<lidar::LidarPoint>& frame) {
  const PerceptionResult result = pipeline.process(frame);
  const auto& s = result.stats;
  EXPECT_EQ(s.input_points, frame.size());
  EXPECT_EQ(s.foreground_points + s.background_points + s.invalid_points, frame.size());
  ASSERT_EQ(result.objects.size(), scene.vehicles.size());
  EXPECT_EQ(s.failed_fits, 0U);
  const auto times = firing_times(frame);
  for (const Detection& object : result.objects) {
    ASSERT_TRUE(object.fit.ok());
    const TrueBox& truth = *nearest_vehicle(scene, object.fit.center);
    // Every point of the object lies on (or, with noise, next to) its vehicle's footprint.
    for (const Eigen::Vector3d& q : object.points) {
      const Eigen::Vector2d p = q.head<2>();
      const Eigen::Vector2d local((p - truth.centre).dot(truth.u()), (p - truth.centre).dot(truth.v()));
      EXPECT_LE(std::abs(local.x()), truth.length / 2.0 + 0.1);
      EXPECT_LE(std::abs(local.y()), truth.width / 2.0 + 0.1);
    }
    // Sweep time: the mean firing time of the object's points.
    double mean_t = 0.0;
    for (const Eigen::Vector3d& q : object.points) {
      const auto t = times.find({q.x(), q.y(), q.z()});
      ASSERT_NE(t, times.end());
      mean_t += static_cast<double>(t->second);
    }
    mean_t /= static_cast<double>(object.points.size());
    EXPECT_NEAR(static_cast<double>(object.sweep_time_ns), mean_t, 1.0);

    const VehicleFix fix = pipeline.correct(
        object, AnnouncedVehicle{{truth.length, truth.width}, YawPrior{truth.yaw + 0.1, 0.17}});
    ASSERT_TRUE(fix.ok());
    const Pose2& pose = fix.corrected.pose;
    EXPECT_LT(std::hypot(pose.x - truth.centre.x(), pose.y - truth.centre.y()), 0.1);
    EXPECT_LT(angle_distance(pose.yaw, truth.yaw), deg_to_rad(3.0));
  }
}

TEST(PerceptionPipeline, RangeImageBackground) {
  BusyStreet s;
  std::mt19937_64 rng(1);
  PerceptionPipeline pipeline({}, test::geometry_of(s.lidar));
  for (const double phase : {0.1, 0.4, 0.7, 0.9})
    pipeline.add_background_frame(test::points_of(test::scan_3d(s.empty, s.lidar, phase, rng)));
  expect_finds_and_corrects_vehicles(pipeline, s.busy,
                                     test::points_of(test::scan_3d(s.busy, s.lidar, 0.55, rng)));
}

TEST(PerceptionPipeline, ReferenceFrameBackground) {
  BusyStreet s;
  std::mt19937_64 rng(2);
  PerceptionConfig config;
  config.background = BackgroundMethod::reference_frame;
  PerceptionPipeline pipeline(config, test::geometry_of(s.lidar));
  pipeline.add_background_frame(test::points_of(test::scan_3d(s.empty, s.lidar, 0.2, rng)));
  pipeline.add_background_frame(test::points_of(test::scan_3d(s.empty, s.lidar, 0.7, rng)));
  expect_finds_and_corrects_vehicles(pipeline, s.busy,
                                     test::points_of(test::scan_3d(s.busy, s.lidar, 0.45, rng)));
}

TEST(PerceptionPipeline, GroundHeightInAnEmptySceneLikeThePilot) {
  BusyStreet s;
  s.busy.wall_radius = 1000.0;  // nothing but ground and vehicles within range
  std::mt19937_64 rng(3);
  PerceptionConfig config;
  config.background = BackgroundMethod::ground_height;
  config.fix.fit.search.method = OrientationSearchMethod::exhaustive;  // the paper's 1 deg search
  const PerceptionPipeline pipeline(config, test::geometry_of(s.lidar));
  expect_finds_and_corrects_vehicles(pipeline, s.busy,
                                     test::points_of(test::scan_3d(s.busy, s.lidar, 0.3, rng)));
}

// The points of each cluster, as sorted coordinates (to compare clusters made by different parts).
using PointSet = std::vector<std::array<double, 3>>;
PointSet sorted(PointSet points) {
  std::sort(points.begin(), points.end());
  return points;
}
PointSet coordinates(const Detection& d) {
  PointSet out;
  for (const Eigen::Vector3d& q : d.points)
    out.push_back({q.x(), q.y(), q.z()});
  return sorted(out);
}
template <typename Points>
PointSet coordinates(const Points& points) {
  PointSet out;
  for (const lidar::LidarPoint& p : points)
    out.push_back({static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
  return sorted(out);
}

// The pipeline's objects are what rsud's SweepClusterer releases for the same frame released whole (a
// PCD frame), and the clusters of the obviously right reference clustering (breadth-first, brute
// force) of the same foreground.
TEST(PerceptionPipeline, ObjectsAreTheClustersRsudAndTheReferenceFind) {
  BusyStreet s;
  std::mt19937_64 rng(4);
  PerceptionConfig config;
  config.background = BackgroundMethod::reference_frame;
  PerceptionPipeline pipeline(config, test::geometry_of(s.lidar));
  BackgroundModel background(background_model_config(config), s.lidar.position.head<2>());
  const auto empty = test::points_of(test::scan_3d(s.empty, s.lidar, 0.5, rng));
  pipeline.add_background_frame(empty);
  background.add_background_frame(empty);
  const auto frame = test::points_of(test::scan_3d(s.busy, s.lidar, 0.1, rng));
  const PerceptionResult result = pipeline.process(frame);

  SweepClusterer swept(SweepConfig{}, config.clustering, s.lidar.position.head<2>(), 10.0, 0.0);
  for (const lidar::LidarPoint& p : frame)
    swept.add(p, background.classify(p) == PointClass::foreground);
  const std::vector<SweptCluster> released = swept.release_all();
  const Clustering reference =
      cluster_reference(frame, background.select_foreground(frame).indices, config.clustering);

  ASSERT_FALSE(result.objects.empty());
  ASSERT_EQ(released.size(), result.objects.size());
  ASSERT_EQ(reference.clusters.size(), result.objects.size());
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    EXPECT_EQ(coordinates(result.objects[i]), coordinates(released[i].points));
    PointSet want;
    for (const std::uint32_t k : reference.clusters[i])
      want.push_back({static_cast<double>(frame[k].x), static_cast<double>(frame[k].y),
                      static_cast<double>(frame[k].z)});
    EXPECT_EQ(coordinates(result.objects[i]), sorted(want));
  }
}

TEST(PerceptionPipeline, Algorithm1IsSelectable) {
  BusyStreet s;
  s.busy.vehicles = {{{15.0, 0.0}, 0.0, 4.89, 1.92}};  // seen from straight ahead: the front only
  s.busy.wall_radius = 1000.0;
  std::mt19937_64 rng(5);
  PerceptionConfig config;
  config.background = BackgroundMethod::ground_height;
  config.fix.method = CorrectionMethod::algorithm1;
  const PerceptionPipeline paper(config, test::geometry_of(s.lidar));
  const auto result = paper.process(test::points_of(test::scan_3d(s.busy, s.lidar, 0.3, rng)));
  ASSERT_GE(result.objects.size(), 1U);  // the front, and maybe the roof on its own
  const Detection* front = &result.objects[0];
  for (const auto& o : result.objects) {
    if (o.points.size() > front->points.size())
      front = &o;
  }
  EXPECT_LT(std::abs(front->fit.center.x() - 12.555), 0.1);  // the front face at x = 15 - 4.89 / 2
  const VehicleFix fix = paper.correct(*front, AnnouncedVehicle{{4.89, 1.92}, std::nullopt});
  ASSERT_TRUE(fix.ok());
  EXPECT_EQ(fix.corrected.resolution, AmbiguityResolution::edge_lengths);
  EXPECT_GT(angle_distance(fix.corrected.pose.yaw, 0.0), deg_to_rad(80.0));  // the paper's off-by-90 case
}

TEST(PerceptionPipeline, BadFramesAreCountedNotCrashed) {
  BusyStreet s;
  std::mt19937_64 rng(6);
  PerceptionPipeline pipeline({}, test::geometry_of(s.lidar));
  pipeline.add_background_frame(test::points_of(test::scan_3d(s.empty, s.lidar, 0.5, rng)));
  EXPECT_TRUE(pipeline.process({}).objects.empty());
  std::vector<lidar::LidarPoint> garbage(100);
  for (std::size_t i = 0; i < garbage.size(); ++i) {
    garbage[i].x = i % 2 == 0 ? std::numeric_limits<float>::quiet_NaN() : 1.0F;
    garbage[i].z = 1.0F;
    garbage[i].ring = static_cast<std::uint16_t>(i % 2 == 0 ? 3 : 60000);
  }
  const auto r = pipeline.process(garbage);
  EXPECT_TRUE(r.objects.empty());
  EXPECT_EQ(r.stats.invalid_points, 100U);
  // Before any background frame, every non-ground point counts as foreground.
  PerceptionConfig config;
  config.background = BackgroundMethod::reference_frame;
  const PerceptionPipeline untrained(config, test::geometry_of(s.lidar));
  const auto frame = test::points_of(test::scan_3d(s.busy, s.lidar, 0.5, rng));
  EXPECT_GT(untrained.process(frame).stats.foreground_points, 1000U);
}

}  // namespace
}  // namespace rsu::perception
