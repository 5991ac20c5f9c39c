// SweepClusterer: clusters are released exactly when the sweep has passed them far enough that no
// later point can join them (the geometric rule in sweep_clusterer.h), computed here independently.
#include "rsu/sweep_clusterer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/angles.h"

namespace rsu::core {
namespace {

constexpr double kHz = 10.0;

// A point at range r and Velodyne azimuth a (clockwise from +x), with the time a 10 Hz sweep reaches a.
LidarPoint at(double r, double azimuth_deg, int rotation = 0) {
  const double a = deg_to_rad(azimuth_deg);
  LidarPoint p;
  p.x = static_cast<float>(r * std::cos(a));
  p.y = static_cast<float>(-r * std::sin(a));
  p.z = 1.0F;
  p.azimuth_rad = static_cast<float>(wrap_angle_positive(a));
  p.time_ns = static_cast<TimeNs>((rotation + azimuth_deg / 360.0) / kHz * 1e9);
  return p;
}

perception::ClusteringConfig clustering() {
  perception::ClusteringConfig c;
  c.tolerance_m = 0.7;
  c.min_points = 5;
  c.max_points = 1000;
  return c;
}

// Feeds a 20-point object at range r spanning azimuths [a0, a1], then background points every 0.05
// deg; returns the sweep azimuth at which the object was released (NaN if never).
double release_azimuth(const SweepConfig& config, double spread_deg, double r, double a0, double a1) {
  SweepClusterer sweep(config, clustering(), Eigen::Vector2d::Zero(), kHz, deg_to_rad(spread_deg));
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

TEST(SweepClusterer, DropsSmallClustersAndCountsThem) {
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
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
  for (int i = 0; i < 20; ++i)
    sweep.add(at(10.0, 355.0 + 0.5 * i), true);  // 355 .. 364.5 deg
  for (double a = 365.0; a < 400.0; a += 0.5)
    sweep.add(at(50.0, a), false);
  const auto released = sweep.release_closed();
  ASSERT_EQ(released.size(), 1U);
  EXPECT_EQ(released[0].points.size(), 20U);
}

TEST(SweepClusterer, WaitsForAnOverlappingOpenCluster) {
  // A near object (3 m, needs ~13 deg past it) and a far one (30 m, ~1.3 deg) at the same azimuths:
  // the far one is closed first but waits so both reach association together.
  SweepClusterer sweep({}, clustering(), Eigen::Vector2d::Zero(), kHz, 0.0);
  for (int i = 0; i < 20; ++i) {
    sweep.add(at(3.0, 40.0 + 0.25 * i), true);
    sweep.add(at(30.0, 40.0 + 0.25 * i), true);
  }
  std::size_t first_release_count = 0;
  double first_release_at = 0.0;
  for (double a = 45.0; a < 80.0 && first_release_count == 0; a += 0.1) {
    sweep.add(at(50.0, a), false);
    const auto released = sweep.release_closed();
    first_release_count = released.size();
    first_release_at = a;
  }
  EXPECT_EQ(first_release_count, 2U);
  EXPECT_GT(first_release_at - 44.75, rad_to_deg(std::asin(0.7 / 3.0)));
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
  LidarPoint bad = at(10.0, 5.0);
  bad.x = std::numeric_limits<float>::quiet_NaN();
  sweep.add(bad, true);
  for (int i = 0; i < 20; ++i)
    sweep.add(at(10.0, 100.0 + 0.2 * i), true);
  EXPECT_TRUE(sweep.release_closed().empty());  // the sweep is still on the object
  const auto all = sweep.release_all();
  ASSERT_EQ(all.size(), 1U);
  EXPECT_EQ(all[0].points.size(), 20U);
  EXPECT_EQ(sweep.stats().invalid_points, 1U);
}

TEST(SweepClusterer, RejectsBadParameters) {
  EXPECT_THROW(SweepClusterer({}, clustering(), Eigen::Vector2d::Zero(), 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(SweepClusterer({}, clustering(), Eigen::Vector2d::Zero(), kHz, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::core
