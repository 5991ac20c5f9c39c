// SPDX-License-Identifier: Apache-2.0
// Euclidean clustering: the grid variant against the obviously-correct reference, and both against
// clusters the test builds on purpose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "perception/euclidean_clustering.h"

namespace rsu::perception {
namespace {

std::vector<std::uint32_t> all_indices(std::size_t n) {
  std::vector<std::uint32_t> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = static_cast<std::uint32_t>(i);
  return v;
}

using ClusterSet = std::set<std::vector<std::uint32_t>>;

ClusterSet as_set(const Clustering& c) {
  return {c.clusters.begin(), c.clusters.end()};
}

// Blobs of various sizes and spreads plus uniform clutter: many merges, chains and singletons.
std::vector<lidar::LidarPoint> blobs_and_clutter(std::mt19937_64& rng) {
  std::vector<lidar::LidarPoint> pts;
  std::uniform_real_distribution<float> where(-40.0F, 40.0F);
  std::uniform_real_distribution<float> height(0.0F, 3.0F);
  std::uniform_int_distribution<int> count(3, 250);
  std::uniform_real_distribution<float> spread(0.1F, 1.5F);
  for (int b = 0; b < 20; ++b) {
    const float cx = where(rng), cy = where(rng), s = spread(rng);
    std::normal_distribution<float> g(0.0F, s);
    const int n = count(rng);
    for (int i = 0; i < n; ++i)
      pts.push_back({cx + g(rng), cy + g(rng), height(rng)});
  }
  for (int i = 0; i < 800; ++i)
    pts.push_back({where(rng), where(rng), height(rng)});
  return pts;
}

TEST(EuclideanClustering, GridEqualsReferenceOnRandomScenes) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(seed);
    const auto pts = blobs_and_clutter(rng);
    const auto subset = all_indices(pts.size());
    for (const ClusterDistance dist : {ClusterDistance::planar, ClusterDistance::spatial}) {
      for (const double tol : {0.4, 0.9}) {
        const ClusteringConfig cfg{.tolerance_m = tol, .min_points = 5, .max_points = 300, .distance = dist};
        const Clustering ref = cluster_reference(pts, subset, cfg);
        const Clustering fast = cluster_grid(pts, subset, cfg);
        EXPECT_EQ(as_set(fast), as_set(ref)) << "seed " << seed << " tol " << tol;
        EXPECT_EQ(fast.clusters, ref.clusters);  // also the same canonical order
        EXPECT_EQ(fast.dropped_small, ref.dropped_small);
        EXPECT_EQ(fast.dropped_large, ref.dropped_large);
        EXPECT_GT(ref.clusters.size(), 3U);
      }
    }
  }
}

TEST(EuclideanClustering, FindsTheClustersTheTestBuilt) {
  // Three groups: a chain of points 0.6 m apart across many cells (one cluster), a tight blob, and a
  // pair 0.71 m apart (two singletons at tolerance 0.7, dropped as small).
  std::vector<lidar::LidarPoint> pts;
  for (int i = 0; i < 20; ++i)
    pts.push_back({0.6F * static_cast<float>(i), 0.0F, 0.0F});  // 0..19
  for (int i = 0; i < 12; ++i)
    pts.push_back({50.0F + 0.01F * static_cast<float>(i), 50.0F, 0.0F});  // 20..31
  pts.push_back({-30.0F, 0.0F, 0.0F});
  pts.push_back({-30.71F, 0.0F, 0.0F});
  const ClusteringConfig cfg{.tolerance_m = 0.7, .min_points = 2, .max_points = 1000};
  for (const auto& result : {cluster_reference(pts, all_indices(pts.size()), cfg),
                             cluster_grid(pts, all_indices(pts.size()), cfg)}) {
    ASSERT_EQ(result.clusters.size(), 2U);
    EXPECT_EQ(result.clusters[0], all_indices(20));
    std::vector<std::uint32_t> blob;
    for (std::uint32_t i = 20; i < 32; ++i)
      blob.push_back(i);
    EXPECT_EQ(result.clusters[1], blob);
    EXPECT_EQ(result.dropped_small, 2U);
  }
}

TEST(EuclideanClustering, PlanarIgnoresHeightSpatialDoesNot) {
  // A vehicle's roof 1.5 m above its sill: one cluster in 2D (Autoware's use_height: false), two in 3D.
  std::vector<lidar::LidarPoint> pts;
  for (int i = 0; i < 10; ++i) {
    pts.push_back({0.3F * static_cast<float>(i), 0.0F, 0.3F});
    pts.push_back({0.3F * static_cast<float>(i), 0.1F, 1.8F});
  }
  const auto idx = all_indices(pts.size());
  EXPECT_EQ(cluster_grid(pts, idx, {.distance = ClusterDistance::planar}).clusters.size(), 1U);
  EXPECT_EQ(cluster_grid(pts, idx, {.distance = ClusterDistance::spatial}).clusters.size(), 2U);
}

TEST(EuclideanClustering, OversizedClustersAreDroppedWholeLikePcl) {
  std::vector<lidar::LidarPoint> pts;
  for (int i = 0; i < 30; ++i)
    pts.push_back({0.1F * static_cast<float>(i), 0.0F, 0.0F});
  for (int i = 0; i < 12; ++i)
    pts.push_back({20.0F + 0.1F * static_cast<float>(i), 0.0F, 0.0F});
  const ClusteringConfig cfg{.tolerance_m = 0.7, .min_points = 10, .max_points = 20};
  for (const auto& r : {cluster_reference(pts, all_indices(pts.size()), cfg),
                        cluster_grid(pts, all_indices(pts.size()), cfg)}) {
    ASSERT_EQ(r.clusters.size(), 1U);
    EXPECT_EQ(r.clusters[0].front(), 30U);
    EXPECT_EQ(r.dropped_large, 1U);
  }
}

TEST(EuclideanClustering, SubsetIndicesReferToTheFrame) {
  std::vector<lidar::LidarPoint> pts;
  for (int i = 0; i < 40; ++i)
    pts.push_back({0.1F * static_cast<float>(i), 0.0F, 0.0F});
  std::vector<std::uint32_t> odd;
  for (std::uint32_t i = 1; i < 40; i += 2)
    odd.push_back(i);
  const auto r = cluster_grid(pts, odd, {.min_points = 5});
  ASSERT_EQ(r.clusters.size(), 1U);
  EXPECT_EQ(r.clusters[0], odd);
}

TEST(EuclideanClustering, BadInputIsCountedNotCrashed) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<lidar::LidarPoint> pts(12, lidar::LidarPoint{1.0F, 1.0F, 0.0F});
  pts[3].x = nan;
  pts[4].y = std::numeric_limits<float>::infinity();
  pts[5].x = 1e30F;
  std::vector<std::uint32_t> idx = all_indices(pts.size());
  idx.push_back(1000);  // outside the frame
  for (const auto& r :
       {cluster_reference(pts, idx, {.min_points = 5}), cluster_grid(pts, idx, {.min_points = 5})}) {
    EXPECT_EQ(r.invalid_points, 4U);
    ASSERT_EQ(r.clusters.size(), 1U);
    EXPECT_EQ(r.clusters[0].size(), 9U);
  }
  EXPECT_TRUE(cluster_grid({}, {}, {}).clusters.empty());
  const auto zero_tol = cluster_grid(pts, all_indices(pts.size()), {.tolerance_m = 0.0, .min_points = 1});
  EXPECT_TRUE(zero_tol.clusters.empty());
  EXPECT_EQ(zero_tol.invalid_points, pts.size());
}

}  // namespace
}  // namespace rsu::perception
