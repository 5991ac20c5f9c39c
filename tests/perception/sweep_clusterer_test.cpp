// SPDX-License-Identifier: Apache-2.0
// SweepClusterer: clusters are released exactly when the sweep has passed them far enough that no
// later point can join them (the geometric rule in sweep_clusterer.h), computed here independently.
#include "perception/sweep_clusterer.h"
#include "lidar/point_eigen.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "common/angles.h"
#include "common/pose.h"
#include "lidar/sensor_model.h"
#include "perception/incremental_clustering.h"
#include "sim/lidar_simulator.h"
#include "sim/scene.h"

namespace rsu::perception {
namespace {

constexpr double kHz = 10.0;

// A point at range r and Velodyne azimuth a (clockwise from +x), with the time a 10 Hz sweep reaches a.
lidar::LidarPoint at(double r, double azimuth_deg, int rotation = 0) {
  const double a = deg_to_rad(azimuth_deg);
  lidar::LidarPoint p;
  p.x = static_cast<float>(r * std::cos(a));
  p.y = static_cast<float>(-r * std::sin(a));
  p.z = 1.0F;
  p.azimuth_rad = static_cast<float>(wrap_angle_positive(a));
  p.time_ns = static_cast<TimeNs>((rotation + azimuth_deg / 360.0) / kHz * 1e9);
  return p;
}

ClusteringConfig clustering() {
  ClusteringConfig c;
  c.tolerance_m = 0.7;
  c.min_points = 5;
  c.max_points = 1000;
  return c;
}

// The stream begins with a background return at azimuth 0, well before the objects of the tests: an
// object the stream begins on is never released whole (CutAtTheStreamsStartIsDroppedThenSeenWhole).
void start_stream(SweepClusterer& sweep, std::uint16_t ring = 0) {
  lidar::LidarPoint p = at(50.0, 0.0);
  p.ring = ring;
  sweep.add(p, false);
}

// Feeds a 20-point object at range r spanning azimuths [a0, a1], then background points every 0.05
// deg; returns the sweep azimuth at which the object was released (NaN if never).
double release_azimuth(const SweepConfig& config, double spread_deg, double r, double a0, double a1) {
  SweepClusterer sweep(config, clustering(), Eigen::Vector2d::Zero(), kHz, deg_to_rad(spread_deg));
  start_stream(sweep);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(r, a0 + (a1 - a0) * i / 19.0), true);
  EXPECT_TRUE(sweep.release_closed().empty());
  for (double a = a1 + 0.05; a < a1 + 120.0; a += 0.05) {
    sweep.add(at(50.0, a), false);
    const auto released = sweep.release_closed();
    if (!released.empty()) {
      EXPECT_EQ(released.size(), 1U);
      EXPECT_EQ(released[0].points.size(), 20U);
      return a;
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

TEST(SweepClusterer, ReleasesOnceNoLaterPointCanJoin) {
  SweepConfig config;
  config.release_margin_deg = 0.5;
  for (const double r : {3.0, 10.0, 30.0}) {
    for (const double spread : {0.0, 8.4}) {
      // Independently: the last point (azimuth a1, range r) is farther than 0.7 m from the wedge of
      // future azimuths once r sin(sweep - spread - margin - a1) > 0.7.
      const double needed = rad_to_deg(std::asin(0.7 / r)) + spread + config.release_margin_deg;
      const double released = release_azimuth(config, spread, r, 40.0, 45.0);
      EXPECT_GE(released - 45.0, needed) << "r " << r << " spread " << spread;
      EXPECT_LE(released - 45.0, needed + 0.06) << "r " << r << " spread " << spread;
    }
  }
}

// Released open (core/prepared_fixes.h): a cluster named by the id and size swept_open gave it goes with
// the closed ones once every laser has swept past it, before the closing angle; one that has grown since
// waits to be closed; and a point that would have joined the released one starts a cluster of its own.
TEST(SweepClusterer, ReleasesANamedOpenClusterOnceSweptUnlessItGrew) {
  SweepConfig config;
  config.release_margin_deg = 0.5;
  SweepClusterer sweep(config, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  // A at 4 m over 40-45 deg (closed asin(0.7 / 4) = 10.1 deg + the margin past 45), B at 4 m over 80-85.
  for (int i = 0; i < 20; ++i)
    sweep.add(at(4.0, 40.0 + 5.0 * i / 19.0), true);
  sweep.add(at(50.0, 45.3), false);  // every laser 44.8 deg: not past A yet
  EXPECT_TRUE(sweep.swept_open().empty());
  sweep.add(at(50.0, 45.6), false);  // 45.1 deg: past A
  std::vector<SweptCluster> given = sweep.swept_open();
  ASSERT_EQ(given.size(), 1U);
  const OpenClusterName a{given[0].id, given[0].points.size()};
  EXPECT_EQ(a.size, 20U);
  EXPECT_TRUE(sweep.release_closed().empty()) << "not closed, and not named";
  const OpenClusterName wrong_size{a.id, a.size + 1};
  EXPECT_TRUE(sweep.release_closed(std::span(&wrong_size, 1)).empty()) << "named with another size";
  std::vector<SweptCluster> released = sweep.release_closed(std::span(&a, 1));
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].id, a.id);
  EXPECT_EQ(released[0].points.size(), 20U);
  EXPECT_EQ(sweep.stats().clusters_released_open, 1U);
  // Six points 0.5 m on from A's last (at 4 m, 7.2 deg): within the tolerance of A, which the closing
  // rule would have joined them to; released open, A is gone, and they are a cluster of their own.
  for (int i = 0; i < 6; ++i)
    sweep.add(at(4.0, 52.2 + 0.1 * i), true);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(4.0, 80.0 + 5.0 * i / 19.0), true);
  sweep.add(at(50.0, 85.6), false);
  given = sweep.swept_open();
  ASSERT_EQ(given.size(), 1U) << "the six points are closed by now; B is swept and open";
  const OpenClusterName b{given[0].id, given[0].points.size()};
  released = sweep.release_closed();
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].points.size(), 6U);
  EXPECT_NE(released[0].id, a.id);
  // B gains a point within the tolerance after it was named: it waits to be closed, then goes whole.
  sweep.add(at(4.0, 85.7), true);
  EXPECT_TRUE(sweep.release_closed(std::span(&b, 1)).empty());
  for (double az = 86.0; az < 100.0; az += 0.5) {
    sweep.add(at(50.0, az), false);
    released = sweep.release_closed(std::span(&b, 1));
    if (!released.empty())
      break;
  }
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].points.size(), 21U);
  EXPECT_EQ(sweep.stats().clusters_released_open, 1U);
  EXPECT_EQ(sweep.stats().clusters_released, 3U);
}

TEST(SweepClusterer, DropsSmallClustersAndCountsThem) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  for (int i = 0; i < 3; ++i)
    sweep.add(at(10.0, 10.0 + 0.1 * i), true);  // 3 points: noise
  for (double a = 11.0; a < 60.0; a += 0.5)
    sweep.add(at(50.0, a), false);
  EXPECT_TRUE(sweep.release_closed().empty());
  EXPECT_EQ(sweep.stats().clusters_dropped_small, 1U);
  EXPECT_EQ(sweep.pending_points(), 0U);
}

TEST(SweepClusterer, ObjectAcrossTheZeroAzimuthIsOneCluster) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(10.0, 355.0 + 0.5 * i), true);  // 355 .. 364.5 deg
  for (double a = 365.0; a < 400.0; a += 0.5)
    sweep.add(at(50.0, a), false);
  const auto released = sweep.release_closed();
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].points.size(), 20U);
}

// A near object (3 m, needs ~13 deg past it) and a farther one at the same azimuths: the farther one
// closes first. Returns how many clusters the first release held and the sweep azimuth it came at.
std::pair<std::size_t, double> first_release_near_and(double far_m, const SweepConfig& config = {}) {
  SweepClusterer sweep(config, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  for (int i = 0; i < 20; ++i) {
    sweep.add(at(3.0, 40.0 + 0.25 * i), true);
    sweep.add(at(far_m, 40.0 + 0.25 * i), true);
  }
  for (double a = 45.0; a < 80.0; a += 0.1) {
    sweep.add(at(50.0, a), false);
    const auto released = sweep.release_closed();
    if (!released.empty())
      return {released.size(), a};
  }
  return {0, 0.0};
}

TEST(SweepClusterer, WaitsForAnOverlappingOpenClusterAtNearbyRanges) {
  // 3 m and 8.5 m apart by 5.5 m, within the 6 m of joint release: the far one waits so that both
  // reach association together.
  const auto [count, at_deg] = first_release_near_and(8.5);
  EXPECT_EQ(count, 2U);
  EXPECT_GT(at_deg - 44.75, rad_to_deg(std::asin(0.7 / 3.0)));
}

TEST(SweepClusterer, ReleasesAClusterFarInRangeFromTheOpenOneAlone) {
  // 3 m and 9.5 m: beyond the joint release gap, the far one goes as soon as it is closed (its bound:
  // asin(0.7 / 9.5) = 4.2 deg past its last point plus the margin), the near one later.
  const auto [count, at_deg] = first_release_near_and(9.5);
  EXPECT_EQ(count, 1U);
  EXPECT_LT(at_deg - 44.75, rad_to_deg(std::asin(0.7 / 9.5)) + 0.5 + 0.2);
  // An infinite gap keeps the rule of old: every overlapping open cluster is waited for.
  SweepConfig always;
  always.joint_release_range_gap_m = std::numeric_limits<double>::infinity();
  EXPECT_EQ(first_release_near_and(30.0, always).first, 2U);
}

// A near object (3 m, 40-45 deg) closes first; a farther one within the gap (8.5 m) at the same azimuths
// and on to 60 deg is still open. The near one cannot be hidden behind it and goes alone, as soon as it
// is closed (asin(0.7 / 3) = 13.5 deg past its last point, plus the 0.5 deg margin, within the 0.25 deg
// step of the points): under the rule before, it waited for the far one (4.7 deg past 59.75 deg).
TEST(SweepClusterer, ANearClusterDoesNotWaitForAFartherOpenOne) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  std::vector<std::pair<std::size_t, double>> releases;  // size, sweep azimuth
  const auto release = [&](double a) {
    for (const SweptCluster& c : sweep.release_closed()) {
      releases.emplace_back(c.points.size(), a);
      EXPECT_FALSE(c.ahead_of_open) << "nothing nearer was open";
    }
  };
  for (int i = 0; i < 80; ++i) {
    const double a = 40.0 + 0.25 * i;
    if (i < 20)
      sweep.add(at(3.0, a), true);
    sweep.add(at(8.5, a), true);
    release(a);
  }
  for (double a = 60.05; a < 90.0; a += 0.05) {
    sweep.add(at(50.0, a), false);
    release(a);
  }
  ASSERT_EQ(releases.size(), 2U);
  EXPECT_EQ(releases[0].first, 20U);
  EXPECT_NEAR(releases[0].second - 44.75, rad_to_deg(std::asin(0.7 / 3.0)) + 0.5, 0.3);
  EXPECT_EQ(releases[1].first, 80U);
  EXPECT_NEAR(releases[1].second - 59.75, rad_to_deg(std::asin(0.7 / 8.5)) + 0.5, 0.1);
}

// The nearer objects a far one was released ahead of: their points swept so far are offered as what may
// hide part of it (RsuCore's occluders) while they stay open; none once they are released too.
TEST(SweepClusterer, OffersTheOpenClustersAReleaseWentAheadOf) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  // And one farther still over the last 1 deg of their span (a dense column of 4 points an azimuth).
  for (int i = 0; i < 20; ++i) {
    sweep.add(at(3.0, 40.0 + 0.25 * i), true);
    sweep.add(at(12.0, 40.0 + 0.25 * i), true);
    for (int k = 0; k < 4 && i >= 16; ++k)
      sweep.add(at(40.0 + 0.1 * k, 40.0 + 0.25 * i), true);
  }
  EXPECT_TRUE(sweep.overtaken_open_points().empty());
  std::vector<std::size_t> released_sizes;
  std::vector<std::vector<std::size_t>> offered;  // each offer's clusters' sizes
  for (double a = 45.0; a < 80.0; a += 0.1) {
    sweep.add(at(50.0, a), false);
    for (const SweptCluster& c : sweep.release_closed())
      released_sizes.push_back(c.points.size());
    std::vector<std::size_t>& sizes = offered.emplace_back();
    for (const std::vector<lidar::LidarPoint>& cluster : sweep.overtaken_open_points())
      sizes.push_back(cluster.size());
  }
  ASSERT_EQ(released_sizes.size(), 3U);
  EXPECT_EQ(released_sizes.back(), 20U);  // the 3 m object, last
  // The 40 m object goes first, ahead of both (their 40 points offered), then the 12 m one, ahead of
  // the 3 m one (its 20), then the 3 m one.
  EXPECT_EQ(released_sizes.front(), 16U);
  const auto first_offer = std::find_if(offered.begin(), offered.end(),
                                        [](const std::vector<std::size_t>& n) { return !n.empty(); });
  ASSERT_NE(first_offer, offered.end());
  EXPECT_EQ(*first_offer, (std::vector<std::size_t>{20U, 20U}));  // one by one, in either order
  EXPECT_NE(std::find(offered.begin(), offered.end(), std::vector<std::size_t>{20U}), offered.end());
  EXPECT_TRUE(offered.back().empty());
  for (const std::vector<std::size_t>& sizes : offered) {
    EXPECT_LE(sizes.size(), 2U);
    for (const std::size_t n : sizes)
      EXPECT_EQ(n, 20U);
  }
}

TEST(SweepClusterer, TimeGoingBackwardsRestartsAndDropsPending) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(10.0, 100.0 + 0.2 * i), true);
  sweep.add(at(50.0, 10.0), false);  // time of azimuth 10 deg: before the object, i.e. backwards
  EXPECT_EQ(sweep.stats().restarts, 1U);
  EXPECT_EQ(sweep.stats().points_dropped_restart, 20U);
  EXPECT_EQ(sweep.pending_points(), 0U);
}

TEST(SweepClusterer, ReleaseAllEndsAFrameAndNonFinitePointsAreCounted) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  lidar::LidarPoint bad = at(10.0, 5.0);
  bad.x = std::numeric_limits<float>::quiet_NaN();
  sweep.add(bad, true);
  start_stream(sweep);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(10.0, 100.0 + 0.2 * i), true);
  EXPECT_TRUE(sweep.release_closed().empty());  // the sweep is still on the object
  const auto all = sweep.release_all();
  ASSERT_EQ(all.size(), 1U);
  EXPECT_EQ(all[0].points.size(), 20U);
  EXPECT_EQ(sweep.stats().invalid_points, 1U);
}

// Points within the tolerance of the LiDAR never close and go stale after half a turn; what they
// joined may fall apart then. B (0.45 m, 30 deg) joins X (0.9 m, 70 deg, 0.63 m from B) and Y (0.3 m,
// 120 deg, 0.54 m from B; 0.74 m from X). When B goes stale X alone is a closed component (released,
// whole) and Y stays pending until it goes stale too.
TEST(SweepClusterer, StalePointsLeaveTheRestClusteredAsWithoutThem) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  for (const auto& [r, a] : {std::pair{0.45, 30.0}, std::pair{0.9, 70.0}, std::pair{0.3, 120.0}}) {
    for (int i = 0; i < 5; ++i)
      sweep.add(at(r, a + 0.1 * i), true);
  }
  std::vector<std::pair<double, std::size_t>> released;  // sweep azimuth, cluster size
  for (double a = 121.0; a < 359.0; a += 1.0) {
    sweep.add(at(50.0, a), false);
    for (const auto& c : sweep.release_closed())
      released.emplace_back(a, c.points.size());
  }
  // B's last point (30.4 deg) is stale once the sweep is past 210.4 deg.
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].first, 211.0);
  EXPECT_EQ(released[0].second, 5U);
  EXPECT_EQ(sweep.stats().points_dropped_stale, 10U);  // B, then Y past 300.4 deg
  EXPECT_EQ(sweep.pending_points(), 0U);
}

// A foreground flood beyond max_pending_points drops the oldest eighth; the rest stays one cluster.
TEST(SweepClusterer, OverflowDropsTheOldestAndKeepsTheRestClustered) {
  SweepConfig config;
  config.max_pending_points = 16;
  SweepClusterer sweep(config, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  start_stream(sweep);
  std::vector<TimeNs> times;
  for (int i = 0; i < 17; ++i) {
    const lidar::LidarPoint p = at(10.0, 100.0 + 0.1 * i);
    times.push_back(p.time_ns);
    sweep.add(p, true);
  }
  EXPECT_EQ(sweep.stats().points_dropped_overflow, 2U);
  EXPECT_EQ(sweep.pending_points(), 15U);
  const auto all = sweep.release_all();
  ASSERT_EQ(all.size(), 1U);
  ASSERT_EQ(all[0].points.size(), 15U);
  for (std::size_t i = 0; i < 15; ++i)
    EXPECT_EQ(all[0].points[i].time_ns, times[i + 2]);  // in arrival order, without the first two
}

// rsud (re)started, or the stream restarted after a gap, while the sweep was on a vehicle: the part
// before the first point was never seen, and a fit of the rest is off (a VLP-16's 98 of ~120 points of
// a car gave a fix 0.16 m off). Dropped and counted; the next rotation sees it whole.
TEST(SweepClusterer, CutAtTheStreamsStartIsDroppedThenSeenWhole) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  for (int rotation = 0; rotation < 2; ++rotation) {
    // The object spans 40-45 deg at 10 m; the stream begins at 42 deg in rotation 0.
    for (int i = 0; i < 20; ++i) {
      const double a = 40.0 + 0.25 * i;
      if (rotation > 0 || a >= 42.0)
        sweep.add(at(10.0, a, rotation), true);
    }
    // A second object at 10 m, 30 deg after the start line (10 sin 30 deg = 5 m > 0.7 m): whole.
    for (int i = 0; i < 20; ++i)
      sweep.add(at(10.0, 72.0 + 0.25 * i, rotation), true);
    std::vector<std::size_t> sizes;
    for (double a = 80.0; a < 200.0; a += 0.5) {
      sweep.add(at(50.0, a, rotation), false);
      for (const auto& c : sweep.release_closed())
        sizes.push_back(c.points.size());
    }
    for (double a = 200.0; a < 360.0; a += 0.5)
      sweep.add(at(50.0, a, rotation), false);
    if (rotation == 0) {
      EXPECT_EQ(sizes, std::vector<std::size_t>({20U})) << "only the second object";
      EXPECT_EQ(sweep.stats().clusters_dropped_cut_at_start, 1U);
    } else {
      EXPECT_EQ(sizes, std::vector<std::size_t>({20U, 20U})) << "both whole";
      EXPECT_EQ(sweep.stats().clusters_dropped_cut_at_start, 1U);
    }
  }
}

TEST(SweepClusterer, RejectsBadParameters) {
  EXPECT_THROW(SweepClusterer({}, clustering(), Eigen::Vector2d::Zero(), 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(SweepClusterer({}, clustering(), Eigen::Vector2d::Zero(), kHz, -1.0), std::invalid_argument);
  for (const double gap : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
    SweepConfig config;
    config.joint_release_range_gap_m = gap;
    EXPECT_THROW(SweepClusterer(config, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0),
                 std::invalid_argument);
  }
}

// --- Laser-aware rule --------------------------------------------------------------------------

std::vector<double> offsets_rad(const lidar::SensorModel& model) {
  std::vector<double> out;
  for (const double o : model.azimuth_offset_deg)
    out.push_back(deg_to_rad(o));
  return out;
}

// Background returns from ONE laser only (the VLP-32C's ring 1, offset -4.2 deg): the rule must
// read the encoder azimuth from whichever laser returns. The spread-only rule takes the largest
// BEAM azimuth as the sweep and so lags by the whole 8.4 deg spread here.
TEST(SweepClusterer, LaserAwareRuleReadsTheEncoderFromAnyLaser) {
  const lidar::SensorModel vlp32c = lidar::make_vlp32c();
  const std::vector<double> offsets = offsets_rad(vlp32c);
  ASSERT_DOUBLE_EQ(vlp32c.azimuth_offset_deg[1], -4.2);
  SweepConfig config;
  config.release_margin_deg = 0.5;
  for (const double r : {4.0, 10.0, 25.0}) {
    for (const bool laser_aware : {true, false}) {
      SweepClusterer sweep =
          laser_aware ? SweepClusterer(config, clustering(), Eigen::Vector2d::Zero(), kHz,
                                       std::span<const double>(offsets))
                      : SweepClusterer(config, clustering(), Eigen::Vector2d::Zero(), kHz, deg_to_rad(8.4));
      start_stream(sweep, 1);
      for (int i = 0; i < 20; ++i) {
        lidar::LidarPoint p = at(r, 40.0 + 0.25 * i);
        p.ring = 1;
        sweep.add(p, true);
      }
      double released_at = std::numeric_limits<double>::quiet_NaN();
      for (double a = 45.0; a < 90.0 && std::isnan(released_at); a += 0.05) {
        lidar::LidarPoint p = at(50.0, a);
        p.ring = 1;
        sweep.add(p, false);
        if (!sweep.release_closed().empty())
          released_at = a;
      }
      // Independently: the ring-1 beam at azimuth b means encoder b + 4.2; the -4.2 deg lasers' wedge
      // starts at b, so the last point (44.75 deg) is clear once b - margin - 44.75 >= asin(0.7 / r);
      // the spread rule needs another 8.4 deg.
      const double needed =
          44.75 + rad_to_deg(std::asin(0.7 / r)) + config.release_margin_deg + (laser_aware ? 0.0 : 8.4);
      EXPECT_GE(released_at, needed) << "r " << r << " laser-aware " << laser_aware;
      EXPECT_LE(released_at, needed + 0.06) << "r " << r << " laser-aware " << laser_aware;
    }
  }
}

TEST(SweepClusterer, LaserAwareRejectsBadTablesAndCountsUnknownRings) {
  const std::vector<double> empty;
  const std::vector<double> nan{0.0, std::numeric_limits<double>::quiet_NaN()};
  const std::vector<double> wide{-1.0, 1.0};  // 115 deg apart
  for (const auto* table : {&empty, &nan, &wide}) {
    EXPECT_THROW(
        SweepClusterer({}, clustering(), Eigen::Vector2d::Zero(), kHz, std::span<const double>(*table)),
        std::invalid_argument);
  }
  const std::vector<double> two{0.0, 0.01};
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, std::span<const double>(two));
  lidar::LidarPoint p = at(10.0, 10.0);
  p.ring = 2;
  sweep.add(p, true);
  EXPECT_EQ(sweep.stats().invalid_points, 1U);
  EXPECT_EQ(sweep.pending_points(), 0U);
}

// The incremental clustering alone against the brute-force cluster_reference: random sparse points
// (near the density at which clusters percolate, so that many components are joined by a single pair
// up to 2 cells apart), added in random order, some components taken out on the way; the components
// left are always exactly the reference's components of the points left.
void check_incremental_against_reference(ClusterDistance distance, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> coordinate(-6.0F, 6.0F);
  std::uniform_real_distribution<float> height(0.0F, 2.0F);
  ClusteringConfig config = clustering();
  config.distance = distance;
  config.min_points = 1;
  config.max_points = std::numeric_limits<std::size_t>::max();
  IncrementalClustering incremental(config);
  std::vector<lidar::LidarPoint> points;
  std::map<std::uint64_t, std::size_t> index_of_seq;
  std::set<std::size_t> present;
  // Compares the components held with the reference's over `present`.
  const auto compare = [&] {
    std::vector<std::uint32_t> subset(present.begin(), present.end());
    const Clustering expected = cluster_reference(points, subset, config);
    std::set<std::vector<std::uint32_t>> expected_sets(expected.clusters.begin(), expected.clusters.end());
    // Read every component: take them all, then add everything back in arrival order.
    std::set<std::vector<std::uint32_t>> components;
    std::vector<std::uint32_t> ids(incremental.components().begin(), incremental.components().end());
    std::vector<PendingPoint> all;
    for (const std::uint32_t c : ids) {
      const ComponentSummary summary = incremental.summary(c);
      std::vector<PendingPoint> members = incremental.take(c);
      EXPECT_EQ(summary.size, members.size());
      std::vector<std::uint32_t> indices;
      for (const PendingPoint& m : members) {
        indices.push_back(static_cast<std::uint32_t>(index_of_seq.at(m.seq)));
        EXPECT_GE(m.seq, summary.first_seq);
      }
      EXPECT_EQ(members.front().seq, summary.first_seq);
      EXPECT_TRUE(std::is_sorted(members.begin(), members.end(),
                                 [](const PendingPoint& a, const PendingPoint& b) { return a.seq < b.seq; }));
      std::sort(indices.begin(), indices.end());
      components.insert(indices);
      all.insert(all.end(), members.begin(), members.end());
    }
    EXPECT_EQ(incremental.size(), 0U);
    EXPECT_EQ(components, expected_sets);
    std::sort(all.begin(), all.end(),
              [](const PendingPoint& a, const PendingPoint& b) { return a.seq < b.seq; });
    for (const PendingPoint& m : all)
      incremental.add(m);
    EXPECT_EQ(incremental.size(), present.size());
  };
  for (std::uint64_t seq = 0; seq < 400; ++seq) {
    lidar::LidarPoint p;
    p.x = coordinate(rng);
    p.y = coordinate(rng);
    p.z = height(rng);
    index_of_seq[seq] = points.size();
    present.insert(points.size());
    points.push_back(p);
    incremental.add({.point = p, .azimuth = static_cast<double>(seq), .seq = seq});
    if (seq % 50 == 49) {
      compare();
      // Take one component out, as a release does.
      const std::uint32_t c = incremental.components().front();
      for (const PendingPoint& m : incremental.take(c))
        present.erase(index_of_seq.at(m.seq));
      compare();
    }
  }
}

TEST(SweepClusterer, IncrementalComponentsAreTheReferenceComponents) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    check_incremental_against_reference(ClusterDistance::planar, seed);
    check_incremental_against_reference(ClusterDistance::spatial, seed);
  }
}

// Exactness against an offline clustering of the whole frame, on simulated VLP-16 and VLP-32C
// frames: every cluster released while the sweep runs is exactly one connected component of the
// frame's foreground (no later point joined it), and it is released by the first packet after the
// closure bound (computed here from the sensor's offset table) is met.
struct PlacedVehicle {
  double range_m;
  double azimuth_deg;  // Velodyne beam azimuth of the centre (clockwise from the sensor's +x)
  double yaw;          // in the map frame
};

// Offline components of `points` (planar distance <= tolerance), by union-find over pairs found
// through a sort on x.
std::vector<int> offline_components(const std::vector<lidar::LidarPoint>& points, double tolerance) {
  std::vector<int> parent(points.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0U);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return points[a].x < points[b].x; });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const lidar::LidarPoint& p = points[order[i]];
    for (std::size_t j = i + 1;
         j < order.size() && static_cast<double>(points[order[j]].x - p.x) <= tolerance; ++j) {
      const lidar::LidarPoint& q = points[order[j]];
      const double dx = static_cast<double>(q.x - p.x);
      const double dy = static_cast<double>(q.y - p.y);
      if (dx * dx + dy * dy <= tolerance * tolerance) {
        parent[static_cast<std::size_t>(find(static_cast<int>(order[i])))] = find(static_cast<int>(order[j]));
      }
    }
  }
  std::vector<int> label(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    label[i] = find(static_cast<int>(i));
  return label;
}

// The release rule as a batch, as the sweep clusterer ran it before it clustered incrementally (issue
// 16): on each packet, every pending foreground point clustered again (cluster_grid), each
// component closed when every point is farther than the tolerance from the future wedge (r sin(behind)
// > d), released when closed, clear of the stream's start and overlapping no open component that starts
// nearer, within the joint release gap; stale
// points (half a turn behind) dropped first. The incremental clusterer must release exactly the same
// clusters, packet by packet, in the same order.
class BatchReleaseReference {
 public:
  BatchReleaseReference(double tolerance, double lag_rad, double joint_gap)
      : tolerance_(tolerance), lag_rad_(lag_rad), joint_gap_(joint_gap) {}

  // `encoder`: the newest unwrapped encoder azimuth; `start_u`: where the stream began (beam azimuth).
  void add(const lidar::LidarPoint& p, double u, double range) { pending_.push_back({p, u, range}); }

  // Each released cluster's points, in arrival order, as (firing time, laser).
  std::vector<std::vector<std::pair<TimeNs, std::uint16_t>>> release(double encoder, double start_u) {
    std::vector<std::vector<std::pair<TimeNs, std::uint16_t>>> out;
    std::erase_if(pending_, [&](const Pending& q) { return q.u < encoder - kPi; });
    const double a_future = encoder - lag_rad_;
    if (pending_.empty() ||
        std::none_of(pending_.begin(), pending_.end(), [&](const Pending& q) { return q.u < a_future; }))
      return out;
    std::vector<lidar::LidarPoint> points;
    for (const Pending& q : pending_)
      points.push_back(q.p);
    const std::vector<int> label = batch_components(points);
    struct State {
      double lo = std::numeric_limits<double>::infinity();
      double hi = -std::numeric_limits<double>::infinity();
      double near = std::numeric_limits<double>::infinity();  // planar range
      double far = -std::numeric_limits<double>::infinity();
      bool closed = true;
      std::size_t first = 0;
    };
    std::map<int, State> state;
    for (std::size_t i = 0; i < pending_.size(); ++i) {
      auto [it, inserted] = state.try_emplace(label[i]);
      State& st = it->second;
      if (inserted)
        st.first = i;
      st.lo = std::min(st.lo, pending_[i].u);
      st.hi = std::max(st.hi, pending_[i].u);
      st.near = std::min(st.near, pending_[i].range);
      st.far = std::max(st.far, pending_[i].range);
      const double behind = a_future - pending_[i].u;
      const double r = pending_[i].range;
      const double distance = behind <= 0.0 ? 0.0 : behind >= kPi / 2.0 ? r : r * std::sin(behind);
      st.closed = st.closed && distance > tolerance_;
    }
    std::vector<std::pair<std::size_t, int>> by_first;
    for (const auto& [l, st] : state)
      by_first.emplace_back(st.first, l);
    std::sort(by_first.begin(), by_first.end());
    std::set<int> taken;
    for (const auto& [first, l] : by_first) {
      const State& st = state.at(l);
      const bool overlaps_open = std::any_of(state.begin(), state.end(), [&](const auto& o) {
        return !o.second.closed && o.second.lo <= st.hi && o.second.hi >= st.lo && o.second.near < st.near &&
               st.near - o.second.far < joint_gap_;
      });
      if (!st.closed || overlaps_open)
        continue;
      taken.insert(l);
      std::vector<std::pair<TimeNs, std::uint16_t>> cluster;
      bool cut = false;
      for (std::size_t i = 0; i < pending_.size(); ++i) {
        if (label[i] != l)
          continue;
        cluster.emplace_back(pending_[i].p.time_ns, pending_[i].p.ring);
        const double ahead = pending_[i].u - start_u;
        cut =
            cut || (ahead < kPi / 2.0 && (ahead <= 0.0 || pending_[i].range * std::sin(ahead) <= tolerance_));
      }
      if (!cut)
        out.push_back(std::move(cluster));
    }
    std::vector<Pending> kept;
    for (std::size_t i = 0; i < pending_.size(); ++i) {
      if (!taken.contains(label[i]))
        kept.push_back(pending_[i]);
    }
    pending_ = std::move(kept);
    return out;
  }

 private:
  struct Pending {
    lidar::LidarPoint p;
    double u;
    double range;
  };
  // cluster_grid over all of them, as the clusterer called it (tested against the brute-force
  // cluster_reference in test_clustering.cpp; offline_components would take seconds a packet here).
  std::vector<int> batch_components(const std::vector<lidar::LidarPoint>& points) const {
    std::vector<std::uint32_t> all(points.size());
    std::iota(all.begin(), all.end(), 0U);
    ClusteringConfig config = clustering();
    config.tolerance_m = tolerance_;
    config.min_points = 1;
    config.max_points = std::numeric_limits<std::size_t>::max();
    const Clustering components = cluster_grid(points, all, config);
    std::vector<int> label(points.size(), -1);
    for (std::size_t c = 0; c < components.clusters.size(); ++c) {
      for (const std::uint32_t i : components.clusters[c])
        label[i] = static_cast<int>(c);
    }
    return label;
  }
  double tolerance_;
  double lag_rad_;
  double joint_gap_;
  std::vector<Pending> pending_;
};

std::vector<std::vector<std::pair<TimeNs, std::uint16_t>>> keys_of(
    const std::vector<SweptCluster>& clusters) {
  std::vector<std::vector<std::pair<TimeNs, std::uint16_t>>> out;
  for (const SweptCluster& c : clusters) {
    out.emplace_back();
    for (const lidar::LidarPoint& p : c.points)
      out.back().emplace_back(p.time_ns, p.ring);
  }
  return out;
}

void check_exact_against_offline(const lidar::SensorModel& model, const std::vector<PlacedVehicle>& placed) {
  const Pose3 mount{.x = 2.0, .y = -3.0, .z = 2.0, .roll = 0.0, .pitch = 0.0, .yaw = 0.3};
  sim::Scene scene;
  scene.ground.half_extent_m = 60.0;
  std::uint32_t id = 1;
  for (const PlacedVehicle& v : placed) {
    const double a = deg_to_rad(v.azimuth_deg);
    const double sx = v.range_m * std::cos(a);  // sensor frame (Velodyne azimuth is clockwise)
    const double sy = -v.range_m * std::sin(a);
    sim::Vehicle vehicle;
    vehicle.id = id++;
    vehicle.trajectory =
        sim::StaticPose{Pose2{mount.x + std::cos(mount.yaw) * sx - std::sin(mount.yaw) * sy,
                              mount.y + std::sin(mount.yaw) * sx + std::cos(mount.yaw) * sy, v.yaw}};
    scene.vehicles.push_back(vehicle);
  }
  const sim::LidarSimulator sim(model, mount, sim::NoiseModel{}, scene);
  // The frame starts with the encoder at 60 deg, so the 0/360 cut is in its middle.
  const TimeNs start = sim.rotation_period_ns() / 6;
  const sim::SimulatedFrame frame = sim.simulate_frame(start);

  // Map frame, as RsuCore hands points over; foreground = vehicle returns (the simulator's truth).
  const Eigen::Isometry3d to_map = mount.to_isometry();
  std::vector<lidar::LidarPoint> points;
  std::vector<bool> foreground;
  for (std::size_t i = 0; i < frame.frame.points.size(); ++i) {
    lidar::LidarPoint p = frame.frame.points[i];
    const Eigen::Vector3d m = to_map * lidar::position_of(p);
    p.x = static_cast<float>(m.x());
    p.y = static_cast<float>(m.y());
    p.z = static_cast<float>(m.z());
    points.push_back(p);
    foreground.push_back(frame.truth[i].surface == sim::SurfaceClass::kVehicle);
  }
  std::vector<lidar::LidarPoint> fg_points;
  std::vector<std::size_t> fg_index;  // stream index of each foreground point
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (foreground[i]) {
      fg_points.push_back(points[i]);
      fg_index.push_back(i);
    }
  }
  ASSERT_GT(fg_points.size(), 100U * placed.size());
  constexpr double kTolerance = 0.7;
  const std::vector<int> label = offline_components(fg_points, kTolerance);
  std::map<std::pair<TimeNs, std::uint16_t>, int> label_of;  // a return is one (firing time, laser)
  std::map<int, std::size_t> component_size;
  for (std::size_t k = 0; k < fg_points.size(); ++k) {
    label_of[{fg_points[k].time_ns, fg_points[k].ring}] = label[k];
    ++component_size[label[k]];
  }

  ClusteringConfig all = clustering();
  all.min_points = 1;
  all.max_points = std::numeric_limits<std::size_t>::max();
  SweepConfig config;
  const std::vector<double> offsets = offsets_rad(model);
  SweepClusterer sweep(config, all, Eigen::Vector2d(mount.x, mount.y), model.rotation_hz(),
                       std::span<const double>(offsets));
  const double min_offset = *std::min_element(offsets.begin(), offsets.end());
  const double margin = deg_to_rad(config.release_margin_deg);

  // The test's own closure bound: the unwrapped encoder azimuth E each cluster needs (largest over its
  // points of a + asin(d / r) - min offset + margin).
  double encoder = -std::numeric_limits<double>::infinity();  // unwrapped newest encoder azimuth
  double previous_encoder = encoder;
  const auto unwrap = [&](double a, double offset) {
    if (!std::isfinite(encoder))
      return a;
    return a + 2.0 * kPi * std::round((encoder + offset - a) / (2.0 * kPi));
  };
  std::map<std::pair<TimeNs, std::uint16_t>, std::pair<double, double>> seen;  // unwrapped azimuth, range

  struct Release {
    int component;
    double needed;            // encoder azimuth of the closure bound
    double previous_encoder;  // at the packet before the release
  };
  std::vector<Release> releases;
  std::set<int> released_components;
  std::size_t released_while_sweeping = 0;
  // What swept_open gave ahead of the release (RsuCore fixes it meanwhile): nothing else comes near
  // these vehicles, so each is released with exactly those points.
  std::map<int, std::vector<std::pair<TimeNs, std::uint16_t>>> given_open;
  std::size_t given_then_released = 0;
  const auto check_released = [&](const std::vector<SweptCluster>& clusters, bool sweeping) {
    for (const SweptCluster& c : clusters) {
      ASSERT_FALSE(c.points.empty());
      const int component = label_of.at({c.points.front().time_ns, c.points.front().ring});
      for (const lidar::LidarPoint& p : c.points) {
        ASSERT_EQ(label_of.at({p.time_ns, p.ring}), component) << "two components released as one";
      }
      if (const auto given = given_open.find(component); given != given_open.end()) {
        EXPECT_EQ(given->second, keys_of({c}).front()) << "given ahead with other points";
        ++given_then_released;
      }
      EXPECT_EQ(c.points.size(), component_size.at(component)) << "released before a later point joined";
      EXPECT_TRUE(released_components.insert(component).second) << "a component released twice";
      if (!sweeping)
        continue;
      ++released_while_sweeping;
      double needed = -std::numeric_limits<double>::infinity();
      for (const lidar::LidarPoint& p : c.points) {
        const auto [u, r] = seen.at({p.time_ns, p.ring});
        needed = std::max(needed, r > kTolerance ? u + std::asin(kTolerance / r) - min_offset + margin
                                                 : std::numeric_limits<double>::infinity());
      }
      EXPECT_GE(encoder, needed - 1e-6) << "released before the closure bound";
      releases.push_back({component, needed, previous_encoder});
    }
  };

  BatchReleaseReference batch(kTolerance, margin - min_offset, config.joint_release_range_gap_m);
  const double max_offset = *std::max_element(offsets.begin(), offsets.end());
  double start_u = 0.0;
  std::size_t batch_releases = 0;
  const auto release_and_compare = [&] {
    const std::vector<SweptCluster> released = sweep.release_closed();
    const auto expected = batch.release(encoder, start_u);
    EXPECT_EQ(keys_of(released), expected) << "not the batch rule's clusters at encoder " << encoder;
    batch_releases += expected.size();
    check_released(released, true);
    const std::vector<SweptCluster> open = sweep.swept_open();
    const auto open_keys = keys_of(open);
    for (const auto& keys : open_keys) {
      const int component = label_of.at(keys.front());
      EXPECT_EQ(released_components.count(component), 0U) << "given after its release";
      EXPECT_TRUE(given_open.emplace(component, keys).second) << "given twice";
    }
  };
  std::int64_t packet = sim.packet_index_at(points.front().time_ns);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::int64_t k = sim.packet_index_at(points[i].time_ns);
    if (k != packet) {  // a packet is complete: RsuCore asks for closed clusters here
      release_and_compare();
      previous_encoder = encoder;
      packet = k;
    }
    const lidar::LidarPoint& p = points[i];
    const double offset = offsets[p.ring];
    const double u = unwrap(static_cast<double>(p.azimuth_rad), offset);
    if (i == 0)
      start_u = u - offset + max_offset;
    encoder = std::max(encoder, u - offset);
    if (foreground[i]) {
      const double r = std::hypot(static_cast<double>(p.x) - mount.x, static_cast<double>(p.y) - mount.y);
      seen[{p.time_ns, p.ring}] = {u, r};
      batch.add(p, u, r);
    }
    sweep.add(p, foreground[i]);
  }
  release_and_compare();
  EXPECT_GE(batch_releases, placed.size());
  check_released(sweep.release_all(), false);
  EXPECT_EQ(released_components.size(), component_size.size());
  // Promptness: a component whose azimuth span overlaps no other one's (so that the wait for an
  // overlapping open cluster never applies) is released by the first packet that meets the bound.
  std::map<int, std::pair<double, double>> span;
  for (const auto& [key, value] : seen) {
    auto [it, inserted] = span.try_emplace(label_of.at(key), value.first, value.first);
    it->second.first = std::min(it->second.first, value.first);
    it->second.second = std::max(it->second.second, value.first);
  }
  std::size_t isolated = 0;
  for (const Release& r : releases) {
    const double lo = span.at(r.component).first, hi = span.at(r.component).second;
    const bool overlaps = std::any_of(span.begin(), span.end(), [&](const auto& other) {
      return other.first != r.component && other.second.first <= hi && other.second.second >= lo;
    });
    if (overlaps)
      continue;
    ++isolated;
    EXPECT_LT(r.previous_encoder, r.needed) << "not released by the first packet that met the bound";
  }
  EXPECT_GE(isolated, 2U);  // vehicles can shed small fragments at overlapping azimuths
  // Each vehicle is released while the sweep runs (fragments may also be), not only at the end.
  EXPECT_GE(released_while_sweeping, placed.size());
  EXPECT_EQ(sweep.stats().points_dropped_stale, 0U);
  EXPECT_EQ(given_then_released, given_open.size());
  EXPECT_GE(given_open.size(), 1U);  // the near vehicles at least: the bound is degrees past them
}

const std::vector<std::vector<PlacedVehicle>> kLayouts = {
    // Across the 0/360 cut at 6 m, broadside at 3.5 m, 10 m and 25 m.
    {{6.0, 0.0, 0.4}, {3.5, 150.0, 1.2}, {10.0, 240.0, 0.0}, {25.0, 300.0, 2.0}},
    // Just before and just after the cut, far and mid range, and near.
    {{15.0, 357.0, 1.0}, {4.5, 110.0, 0.0}, {30.0, 190.0, 0.7}, {8.0, 270.0, 1.9}, {20.0, 4.0, 0.2}},
};

TEST(SweepClusterer, ExactAgainstOfflineClusteringVlp16) {
  for (const auto& layout : kLayouts)
    check_exact_against_offline(lidar::make_vlp16(), layout);
}

TEST(SweepClusterer, ExactAgainstOfflineClusteringVlp32c) {
  for (const auto& layout : kLayouts)
    check_exact_against_offline(lidar::make_vlp32c(), layout);
}

// A dense sensor's near cars (issue 16): 128 rings x 1808 columns, cars at 3.6 and 6 m, thousands of
// points each, joined point by point (incremental_clustering.h) while the sweep runs. (Two cars: the
// batch reference re-clusters every pending point on each packet, ~5 s under ASan with four.)
TEST(SweepClusterer, ExactAgainstOfflineClusteringDenseNearCars) {
  // (Each car clear of the frame's start at 60 deg: one seen on both sides of it is two objects.)
  check_exact_against_offline(lidar::make_generic(128), {{3.6, 120.0, 0.0}, {6.0, 220.0, 1.0}});
}

}  // namespace
}  // namespace rsu::perception
