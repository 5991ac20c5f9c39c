// SPDX-License-Identifier: Apache-2.0
// Background removal: the hash grid against brute force, and the three methods against the labels the
// synthetic scene knows.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "perception/ground_height_filter.h"
#include "perception/point_hash_grid.h"
#include "perception/range_image_background.h"
#include "perception/reference_frame_background.h"
#include "synthetic_scene.h"

namespace rsu::perception {
namespace {

using test::HitKind;

std::vector<GridPoint> random_cloud(std::size_t n, float extent, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> u(-extent, extent);
  std::vector<GridPoint> pts(n);
  for (auto& p : pts) {
    p = {u(rng), u(rng), u(rng) * 0.05F};
  }
  return pts;
}

bool brute_any_within(const std::vector<GridPoint>& pts, const GridPoint& q, double r, bool spatial) {
  for (const auto& p : pts) {
    const double dx = static_cast<double>(p.x) - static_cast<double>(q.x);
    const double dy = static_cast<double>(p.y) - static_cast<double>(q.y);
    const double dz = spatial ? static_cast<double>(p.z) - static_cast<double>(q.z) : 0.0;
    if (std::sqrt(dx * dx + dy * dy + dz * dz) <= r) {
      return true;
    }
  }
  return false;
}

TEST(PointHashGrid, AnyWithinMatchesBruteForce) {
  std::mt19937_64 rng(7);
  for (const GridDims dims : {GridDims::spatial, GridDims::planar}) {
    const auto pts = random_cloud(3000, 10.0F, rng);
    const auto queries = random_cloud(3000, 11.0F, rng);
    for (const float r : {0.15F, 0.3F, 0.5F}) {
      const PointHashGrid grid(pts, r, dims);
      std::size_t hits = 0;
      for (const auto& q : queries) {
        const bool expected = brute_any_within(pts, q, static_cast<double>(r), dims == GridDims::spatial);
        ASSERT_EQ(grid.any_within(q, r), expected) << "r=" << r << " q=" << q.x << "," << q.y << "," << q.z;
        hits += expected ? 1 : 0;
      }
      // Both answers occur, so the comparison means something.
      EXPECT_GT(hits, 100U);
      EXPECT_LT(hits, queries.size() - 100U);
    }
  }
}

TEST(PointHashGrid, SkipsNonFiniteAndHugeCoordinates) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<GridPoint> pts = {
      {0, 0, 0}, {nan, 0, 0}, {1e30F, 0, 0}, {0, std::numeric_limits<float>::infinity(), 0}};
  const PointHashGrid grid(pts, 0.3F, GridDims::spatial);
  EXPECT_EQ(grid.points().size(), 1U);
  EXPECT_EQ(grid.skipped(), 3U);
  EXPECT_TRUE(grid.any_within({0.1F, 0, 0}, 0.3F));
  EXPECT_FALSE(grid.any_within({nan, 0, 0}, 0.3F));
  EXPECT_FALSE(grid.any_within({1e30F, 0, 0}, 0.3F));
  const PointHashGrid no_cells(pts, 0.0F, GridDims::spatial);  // invalid cell size: empty, no crash
  EXPECT_EQ(no_cells.points().size(), 0U);
  EXPECT_FALSE(no_cells.any_within({0, 0, 0}, 0.3F));
}

TEST(ReferenceFrameBackground, SameAnswerAsNearestNeighbourTest) {
  std::mt19937_64 rng(11);
  const auto ref = random_cloud(4000, 8.0F, rng);
  const auto cur = random_cloud(4000, 9.0F, rng);
  std::vector<lidar::LidarPoint> ref_pts, cur_pts;
  for (const auto& p : ref)
    ref_pts.push_back({p.x, p.y, p.z});
  for (const auto& p : cur)
    cur_pts.push_back({p.x, p.y, p.z});
  const double r = 0.3;
  const ReferenceFrameBackground bg(ref_pts, {.match_radius_m = r});
  const ForegroundSelection sel = bg.select_foreground(cur_pts);
  std::vector<std::uint32_t> expected;
  for (std::size_t i = 0; i < cur.size(); ++i) {
    // Foreground iff the nearest reference point is farther than r.
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& p : ref) {
      const double dx = static_cast<double>(p.x - cur[i].x), dy = static_cast<double>(p.y - cur[i].y),
                   dz = static_cast<double>(p.z - cur[i].z);
      nearest = std::min(nearest, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    if (nearest > r)
      expected.push_back(static_cast<std::uint32_t>(i));
  }
  EXPECT_EQ(sel.indices, expected);
  EXPECT_EQ(sel.background + sel.indices.size(), cur.size());
  EXPECT_GT(expected.size(), 200U);
  EXPECT_GT(sel.background, 200U);
}

TEST(GroundHeightFilter, KeepsExactlyThePointsAboveThreshold) {
  const std::vector<lidar::LidarPoint> pts = {{0, 0, 0.0F},
                                              {1, 0, 0.19F},
                                              {2, 0, 0.21F},
                                              {3, 0, 1.5F},
                                              {4, 0, std::numeric_limits<float>::quiet_NaN()},
                                              {5, 0, -0.5F}};
  const GroundHeightFilter filter({.ground_z = 0.0, .min_height = 0.2});
  const auto sel = filter.select_foreground(pts);
  EXPECT_EQ(sel.indices, (std::vector<std::uint32_t>{2, 3}));
  EXPECT_EQ(sel.background, 3U);
  EXPECT_EQ(sel.invalid, 1U);
  const GroundHeightFilter raised({.ground_z = 1.0, .min_height = 0.2});
  EXPECT_EQ(raised.select_foreground(pts).indices, (std::vector<std::uint32_t>{3}));
}

// The synthetic street: ground, a round wall, and (in the test frame) two vehicles.
struct Street {
  test::Scene3d empty;
  test::Scene3d busy;
  test::Lidar3d lidar = test::small_lidar(16);
  Street() {
    lidar.azimuth_steps = 900;
    busy.vehicles = {{{12.0, 3.0}, 0.3, 4.89, 1.92}, {{-6.0, -15.0}, 1.2, 4.5, 1.8}};
  }
};

struct Scores {
  double recall;          // vehicle points kept
  double false_positive;  // ground/wall points kept, as a fraction of them
};

template <class Classifier>
Scores score(const std::vector<test::LabelledPoint>& frame, Classifier&& classify, bool skip_low_vehicle) {
  std::size_t veh = 0, veh_kept = 0, bg = 0, bg_kept = 0;
  for (const auto& lp : frame) {
    const bool fg = classify(lp.point) == PointClass::foreground;
    if (lp.kind == HitKind::vehicle) {
      if (skip_low_vehicle && lp.point.z < 0.5F)
        continue;  // within the margins of the ground by design
      ++veh;
      veh_kept += fg ? 1 : 0;
    } else {
      ++bg;
      bg_kept += fg ? 1 : 0;
    }
  }
  EXPECT_GT(veh, 50U);
  return {static_cast<double>(veh_kept) / static_cast<double>(veh),
          static_cast<double>(bg_kept) / static_cast<double>(bg)};
}

TEST(RangeImageBackground, SeparatesVehiclesFromLearnedBackground) {
  Street s;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  RangeImageBackground model(s.lidar.position.head<2>(), {.azimuth_bins = 900});
  for (int f = 0; f < 8; ++f) {
    model.add_training_frame(test::points_of(test::scan_3d(s.empty, s.lidar, phase(rng), rng)));
  }
  EXPECT_EQ(model.rings(), 16);
  EXPECT_EQ(model.training_frames(), 8);
  const auto frame = test::scan_3d(s.busy, s.lidar, phase(rng), rng);
  const Scores sc = score(
      frame, [&](const lidar::LidarPoint& p) { return model.classify(p); }, true);
  EXPECT_GT(sc.recall, 0.99);
  EXPECT_LT(sc.false_positive, 0.002);
}

TEST(RangeImageBackground, NeverReturnedCellsAreSkyAndAnythingThereIsForeground) {
  Street s;
  s.empty.wall_height = 4.0;  // upper rings see nothing
  std::mt19937_64 rng(5);
  RangeImageBackground model(s.lidar.position.head<2>(), {.azimuth_bins = 900});
  model.add_training_frame(test::points_of(test::scan_3d(s.empty, s.lidar, 0.3, rng)));
  // Ring 15 points 15 deg up: at the 40 m wall that is z = 12.7 m, above the wall: sky.
  EXPECT_TRUE(std::isinf(model.background_range(15, 1.0F)));
  EXPECT_NEAR(static_cast<double>(model.background_range(0, 1.0F)), 2.0 / std::tan(15.0 * test::kPi / 180.0),
              0.1);
  lidar::LidarPoint bird{5.0F, 0.0F, 3.3F};
  bird.ring = 15;
  bird.azimuth_rad = 0.0F;
  EXPECT_EQ(model.classify(bird), PointClass::foreground);
}

TEST(RangeImageBackground, InvalidPointsAreCountedNotCrashed) {
  RangeImageBackground model(Eigen::Vector2d::Zero(), {.max_rings = 64});
  std::vector<lidar::LidarPoint> train(10);
  for (std::size_t i = 0; i < train.size(); ++i) {
    train[i] = {10.0F, 0.0F, 0.0F};
    train[i].ring = static_cast<std::uint16_t>(i);
  }
  model.add_training_frame(train);
  std::vector<lidar::LidarPoint> frame(4, lidar::LidarPoint{5.0F, 0.0F, 0.0F});
  frame[0].x = std::numeric_limits<float>::quiet_NaN();
  frame[1].ring = 64;  // beyond max_rings: garbage
  frame[2].azimuth_rad = std::numeric_limits<float>::infinity();
  frame[3].azimuth_rad = 7.5F;  // outside [0, 2 pi): wrapped, still judged
  const auto sel = model.select_foreground(frame);
  EXPECT_EQ(sel.invalid, 3U);
  EXPECT_EQ(sel.indices, (std::vector<std::uint32_t>{3}));  // 5 m is well in front of the 10 m background
  EXPECT_TRUE(model.select_foreground({}).indices.empty());
}

TEST(ReferenceFrameBackground, SeparatesVehiclesWithGroundPrefilter) {
  Street s;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  std::vector<lidar::LidarPoint> reference;
  for (int f = 0; f < 3; ++f) {
    const auto pts = test::points_of(test::scan_3d(s.empty, s.lidar, phase(rng), rng));
    reference.insert(reference.end(), pts.begin(), pts.end());
  }
  const ReferenceFrameBackground model(reference);
  const GroundHeightFilter ground;
  const auto frame = test::scan_3d(s.busy, s.lidar, phase(rng), rng);
  const Scores sc = score(
      frame,
      [&](const lidar::LidarPoint& p) {
        const PointClass c = ground.classify(p);
        return c == PointClass::foreground ? model.classify(p) : c;
      },
      true);
  EXPECT_GT(sc.recall, 0.99);
  EXPECT_LT(sc.false_positive, 0.01);
}

}  // namespace
}  // namespace rsu::perception
