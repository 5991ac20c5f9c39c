// SPDX-License-Identifier: Apache-2.0
// The lasers' traces near a fitted face (face_traces.h), on hand-made returns whose runs, spans and slopes
// the tests know by construction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "perception/face_traces.h"
#include "perception/lidar_geometry.h"

namespace rsu::perception {
namespace {

// An edge along x from 0 to 4 m, its support band 0.15 m.
const FaceLine kEdge{Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0), 4.0, 0.15};

TEST(FaceTraces, LineHelpersAgreeWithTheirDefinitions) {
  std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0};
  EXPECT_DOUBLE_EQ(median_in_place(v), 3.0);
  // For n points evenly at 0 .. l, sqrt(12) times their RMS spread is l sqrt((n + 1) / (n - 1)).
  const std::vector<double> along = {0.0, 1.0, 2.0, 3.0, 4.0};
  EXPECT_NEAR(spread_length(along), 4.0 * std::sqrt(6.0 / 4.0), 1e-12);
  EXPECT_DOUBLE_EQ(spread_length(std::vector<double>{2.0}), 0.0);
  const std::vector<double> across = {0.1, 0.35, 0.6, 0.85, 1.1};  // 0.1 + 0.25 s
  EXPECT_NEAR(least_squares_slope(along, across), 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(least_squares_slope(std::vector<double>{1.0, 1.0}, std::vector<double>{0.0, 2.0}), 0.0);
}

// Laser 0 along the edge, leaving its band once (a run of 6, then 2, then 4 returns); a return beyond the
// depth neither ends nor joins a run; laser 1's returns interleaved end none of laser 0's.
struct Scene {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::size_t> ranks;
  void add(double s, double n, double z, std::size_t laser) {
    points.emplace_back(s, n, z);
    ranks.push_back(laser);
  }
};

Scene scene() {
  Scene sc;
  for (int i = 0; i < 6; ++i) {
    sc.add(0.2 + 0.1 * i, 0.0, 0.5, 0);
    sc.add(0.25 + 0.1 * i, 0.9, 1.2, 1);  // laser 1, off the band within the depth
  }
  sc.add(0.85, 3.0, 0.5, 0);  // beyond the depth: ignored
  sc.add(0.9, 0.5, 0.5, 0);   // off the band: ends the run of 6
  sc.add(1.0, 0.1, 0.5, 0);   // a run of 2
  sc.add(1.1, -0.1, 0.5, 0);
  sc.add(1.2, -0.6, 0.5, 0);   // ends it
  for (int i = 0; i < 4; ++i)  // a run of 4 tilted 0.05 m per m, high up
    sc.add(2.0 + 0.5 * i, 0.05 * (0.5 * i), 1.5, 0);
  sc.add(-0.5, 0.0, 0.5, 0);  // beyond the edge's end and band: ignored
  sc.add(1.5, 0.0, 0.5, LaserLookup::kNone);
  return sc;
}

TEST(FaceTraces, RunsSplitWhereTheTraceLeavesTheBand) {
  const Scene sc = scene();
  const std::vector<TracePoint> near = traces_near(sc.points, sc.ranks, kEdge, 1.0);
  ASSERT_EQ(near.size(), (6U + 1U + 2U + 1U + 4U) + 6U);
  for (const TracePoint& p : near) {
    EXPECT_DOUBLE_EQ(p.along, sc.points[p.index].x());
    EXPECT_DOUBLE_EQ(p.across, -sc.points[p.index].y());  // n: across, to the edge's right
    EXPECT_EQ(p.laser, sc.ranks[p.index]);
  }
  const TraceRuns runs = trace_runs(near, 2, kEdge);
  ASSERT_EQ(runs.size, (std::vector<std::size_t>{6, 2, 4}));  // laser 1 has none in the band
  for (std::size_t i = 0; i < near.size(); ++i)
    EXPECT_EQ(runs.run[i] == LaserLookup::kNone, std::abs(near[i].across) > kEdge.band) << i;
  const std::vector<bool> crossing = crossing_returns(near, runs, sc.points.size(), 3);
  std::vector<std::size_t> marked;
  for (std::size_t i = 0; i < crossing.size(); ++i) {
    if (crossing[i])
      marked.push_back(i);
  }
  // The run of 2: the returns at 1.0 and 1.1 m.
  ASSERT_EQ(marked.size(), 2U);
  EXPECT_DOUBLE_EQ(sc.points[marked[0]].x(), 1.0);
  EXPECT_DOUBLE_EQ(sc.points[marked[1]].x(), 1.1);
}

TEST(FaceTraces, SpanTracesKeepTheSpanAwayFromTheCornersOnTheFullPlan) {
  const Scene sc = scene();
  const std::vector<TracePoint> near = traces_near(sc.points, sc.ranks, kEdge, 1.0);
  const std::vector<SpanTrace> span = span_traces(near, 2, kEdge, 0.0, 1.0);  // up to 1 m: not the run of 4
  ASSERT_EQ(span.size(), 2U);
  EXPECT_EQ(span[0].along.size(), 6U + 1U + 2U + 1U);
  EXPECT_EQ(span[0].in_band, 8U);
  EXPECT_TRUE(span[1].along.empty());  // laser 1 is 1.2 m up
  for (const double s : span[0].along)
    EXPECT_TRUE(s >= kEdge.band && s <= kEdge.length - kEdge.band);
  EXPECT_EQ(span_traces(near, 2, kEdge, -1.0, 1.0)[0].along.size(), 0U);  // the road 1 m lower
}

// Returns near an edge along x: a run of slope k (laser 0) and a level one (laser 1), interleaved as two
// lasers' returns come. A run of slope k with no noise departs by k over half the face; noise takes twice
// the slope's standard error off it; runs shorter than min_points say nothing.
TEST(FaceTraces, RunTiltIsTheSteepestSlopeBeyondItsError) {
  std::vector<TracePoint> near;
  std::vector<double> along;
  for (int i = 0; i < 5; ++i) {
    along.push_back(0.4 * i);
    near.push_back({0.4 * i, -0.1 + 0.08 * 0.4 * i, 1.0, 0, near.size()});
    near.push_back({2.0 + 0.4 * i, 0.0, 1.0, 1, near.size()});
  }
  const TraceRuns runs = trace_runs(near, 2, kEdge);
  ASSERT_EQ(runs.size.size(), 2U);
  EXPECT_NEAR(run_tilt_departure(near, runs, 4.0, 0.0, 3), 0.5 * 4.0 * 0.08, 1e-12);
  const double error = 0.02 * std::sqrt(12.0 / 5.0) / spread_length(along);
  EXPECT_NEAR(run_tilt_departure(near, runs, 4.0, 0.02, 3), 0.5 * 4.0 * (0.08 - 2.0 * error), 1e-12);
  EXPECT_DOUBLE_EQ(run_tilt_departure(near, runs, 4.0, 0.2, 3), 0.0);  // within its error
  EXPECT_DOUBLE_EQ(run_tilt_departure(near, runs, 4.0, 0.0, 6), 0.0);  // too short
}

}  // namespace
}  // namespace rsu::perception
