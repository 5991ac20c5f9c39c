// SPDX-License-Identifier: Apache-2.0
// The grown footprint's overlap with a box against an independent test (corners inside, edges
// crossing), and the gatherer's hold for a farther cluster still open where the vehicle may be
// (perception::SweptCluster::open_beyond) or a nearer one (ahead_of_open; issue 16), and the one
// detection's thinning a held vehicle carries to its fix.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/grown_footprint.h"
#include "core/sweep_position.h"
#include "core/vehicle_gatherer.h"

namespace rsu::core {
namespace {

using Polygon = std::array<Eigen::Vector2d, 4>;

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool inside(const Polygon& p, const Eigen::Vector2d& q) {
  bool left = false;
  bool right = false;
  for (std::size_t i = 0; i < 4; ++i) {
    const double c = cross(p[(i + 1) % 4] - p[i], q - p[i]);
    left = left || c > 0.0;
    right = right || c < 0.0;
  }
  return !(left && right);
}

bool segments_cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                    const Eigen::Vector2d& d) {
  const double d1 = cross(b - a, c - a);
  const double d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c);
  const double d4 = cross(d - c, b - c);
  return ((d1 > 0.0) != (d2 > 0.0)) && ((d3 > 0.0) != (d4 > 0.0));
}

// Two convex quadrilaterals share a place exactly when a corner of one lies in the other or two edges cross.
bool reference_overlap(const Polygon& a, const Polygon& b) {
  for (std::size_t i = 0; i < 4; ++i) {
    if (inside(a, b[i]) || inside(b, a[i]))
      return true;
    for (std::size_t j = 0; j < 4; ++j) {
      if (segments_cross(a[i], a[(i + 1) % 4], b[j], b[(j + 1) % 4]))
        return true;
    }
  }
  return false;
}

tracking::VehicleHypothesis car(const Eigen::Vector2d& centre, double yaw) {
  tracking::VehicleHypothesis v;
  v.vehicle_id = 7;
  v.centre = centre;
  v.yaw = yaw;
  v.covariance = Eigen::Vector3d(0.01, 0.01, 1e-4).asDiagonal();
  v.size = {4.6, 1.8, 1.5};
  return v;
}

// The footprint grown by the minimum margin and one sigma of the centre (GatheringConfig: 0.4 m; the
// car's sigma 0.1 m), its corners in order around it.
Polygon tight_footprint(const tracking::VehicleHypothesis& v) {
  const double grow = GatheringConfig{}.min_margin_m + 0.1;
  const Eigen::Vector2d half(0.5 * v.size.length_m + grow, 0.5 * v.size.width_m + grow);
  const Eigen::Rotation2Dd r(v.yaw);
  return {v.centre + r * Eigen::Vector2d(-half.x(), -half.y()),
          v.centre + r * Eigen::Vector2d(half.x(), -half.y()),
          v.centre + r * Eigen::Vector2d(half.x(), half.y()),
          v.centre + r * Eigen::Vector2d(-half.x(), half.y())};
}

constexpr TimeNs kNow = 2'000'000'000;

// A single-laser sensor at 10 Hz whose newest point, fired at kNow, is just past a car 10 m east at
// y < 0 (clockwise) and short of its footprints' far corners.
SweepPosition sweep_past_car(const LidarMount& mount) {
  lidar::SweepGeometry geometry;
  geometry.rotation_hz = 10.0;
  geometry.ring_azimuth_offset_rad = {0.0};
  SweepPosition sweep(mount, 0.7, 0.5, geometry);
  lidar::LidarPoint newest;
  newest.azimuth_rad = static_cast<float>(std::atan2(3.0, 10.0));
  newest.time_ns = kNow;
  sweep.advance(std::span<const lidar::LidarPoint>(&newest, 1));
  return sweep;
}

TEST(GrownFootprint, TightlyOverlapsABoxExactlyWhenTheyShareAPlace) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-6.0, 6.0);
  std::uniform_real_distribution<double> extent(0.05, 4.0);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  const GatheringConfig config;
  int overlapping = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const tracking::VehicleHypothesis vehicle = car({coordinate(rng), coordinate(rng)}, angle(rng));
    const GrownFootprint footprint(vehicle, config);
    const Eigen::Vector2d lo(coordinate(rng), coordinate(rng));
    const Eigen::AlignedBox2d box(lo, lo + Eigen::Vector2d(extent(rng), extent(rng)));
    const Polygon box_ring = {box.min(), Eigen::Vector2d(box.max().x(), box.min().y()), box.max(),
                              Eigen::Vector2d(box.min().x(), box.max().y())};
    const bool expected = reference_overlap(tight_footprint(vehicle), box_ring);
    overlapping += expected ? 1 : 0;
    EXPECT_EQ(footprint.tightly_overlaps(box), expected) << "trial " << trial;
  }
  EXPECT_GT(overlapping, 500);  // both outcomes well represented
  EXPECT_LT(overlapping, 4500);
  // An empty box shares no place.
  EXPECT_FALSE(GrownFootprint(car({0.0, 0.0}, 0.0), config).tightly_overlaps(Eigen::AlignedBox2d()));
}

// The closed cluster of the car 10 m east (car({10.0, -0.5}, 0)): its near side, swept 1 ms before kNow.
perception::Detection near_side() {
  perception::Detection d;
  d.sweep_time_ns = kNow - 1'000'000;
  for (double x = 8.0; x <= 12.0; x += 0.1)
    d.points.emplace_back(x, 0.35, 0.8);
  return d;
}

// The one detection assigned to the one vehicle.
tracking::AssociationResult assigned_to_it() {
  tracking::AssociationResult association;
  association.pairs.push_back({0, 0, 0.5});
  return association;
}

// A car 10 m east of the LiDAR, its cluster closed and assigned to it, tightly inside its footprint. Alone
// it is released at once; with a farther cluster still open inside its footprint (its own roof seen from
// high up) it is held until the sweep has passed the grown footprint; with one open 3 m beyond it
// (another car passing behind it) it is released at once.
TEST(VehicleGatherer, HoldsForAFartherOpenClusterOnlyWhereTheVehicleMayBe) {
  const LidarMount mount(Pose3{});
  const SweepPosition sweep = sweep_past_car(mount);
  const tracking::VehicleHypothesis vehicle = car({10.0, -0.5}, 0.0);
  const perception::Detection own = near_side();
  const tracking::AssociationResult association = assigned_to_it();
  const auto release_at = [&](const std::vector<Eigen::AlignedBox2d>& open_beyond) {
    VehicleGatherer gatherer({}, {}, mount.xy());
    perception::Detection d = own;
    d.open_beyond = open_beyond;
    std::vector<perception::Detection> detections{d};
    gatherer.gather(std::move(detections), std::span<const tracking::VehicleHypothesis>(&vehicle, 1),
                    association, sweep);
    EXPECT_EQ(gatherer.held().size(), 1U);
    return gatherer.held().empty() ? TimeNs{0} : gatherer.held().front().release_at;
  };
  EXPECT_EQ(release_at({}), own.sweep_time_ns);
  const Eigen::AlignedBox2d roof(Eigen::Vector2d(9.0, -1.2), Eigen::Vector2d(11.0, -0.3));
  const TimeNs held = release_at({roof});
  EXPECT_GT(held, kNow);
  const GrownFootprint footprint(vehicle, GatheringConfig{});
  EXPECT_EQ(held, sweep.passed_time(footprint.corners()));
  const Eigen::AlignedBox2d behind(Eigen::Vector2d(8.0, -6.0), Eigen::Vector2d(12.0, -4.5));
  EXPECT_FALSE(footprint.tightly_overlaps(behind));
  EXPECT_EQ(release_at({behind}), own.sweep_time_ns);
}

// The fix of a vehicle gathered from one detection takes that detection's thinning (the thinning of the
// same points); once a second part is gathered the union's is made anew (none carried).
TEST(VehicleGatherer, CarriesTheOneDetectionsThinning) {
  const LidarMount mount(Pose3{});
  const SweepPosition sweep = sweep_past_car(mount);
  const tracking::VehicleHypothesis vehicle = car({10.0, -0.5}, 0.0);
  perception::Detection own = near_side();
  own.thinning = perception::AzimuthThinning{3, {own.points.front(), own.points.back()}};
  const tracking::AssociationResult association = assigned_to_it();
  VehicleGatherer gatherer({}, {}, mount.xy());
  const auto gather = [&] {
    std::vector<perception::Detection> detections{own};
    gatherer.gather(std::move(detections), std::span<const tracking::VehicleHypothesis>(&vehicle, 1),
                    association, sweep);
  };
  gather();
  ASSERT_EQ(gatherer.held().size(), 1U);
  const HeldVehicle& held = gatherer.held().front();
  ASSERT_TRUE(held.thinning.has_value());
  EXPECT_EQ(held.thinning->stride, 3);
  EXPECT_EQ(held.thinning->points, own.thinning->points);
  gather();
  ASSERT_EQ(gatherer.held().size(), 1U);
  EXPECT_EQ(gatherer.held().front().parts, 2U);
  EXPECT_FALSE(gatherer.held().front().thinning.has_value());
}

// The same car behind a nearer cluster still open in its line of sight (a car passing in front): held
// until the sweep has passed its own place, whichever of its two footprints that reaches first. Stated
// 0.5 m uncertain (the fleet's announcements), the one grown by 2.5 sigma reaches 1.85 m beyond the box
// and the one grown by the minimum margin and one sigma 0.9 m: the hold ends with the latter, earlier.
// Stated 0.1 m, the grown one (0.4 m) is the smaller. A car whose assigned cluster lies outside its
// tight footprint (maybe a neighbour's) is held for the whole grown one, as before.
TEST(VehicleGatherer, BehindANearerOpenClusterHoldsUntilTheSweepPassedTheSmallerFootprint) {
  const LidarMount mount(Pose3{});
  const SweepPosition sweep = sweep_past_car(mount);
  perception::Detection seen = near_side();
  seen.ahead_of_open = true;
  const tracking::AssociationResult association = assigned_to_it();
  const auto release_at = [&](const tracking::VehicleHypothesis& vehicle, const perception::Detection& d) {
    VehicleGatherer gatherer({}, {}, mount.xy());
    std::vector<perception::Detection> detections{d};
    gatherer.gather(std::move(detections), std::span<const tracking::VehicleHypothesis>(&vehicle, 1),
                    association, sweep);
    EXPECT_EQ(gatherer.held().size(), 1U);
    return gatherer.held().empty() ? TimeNs{0} : gatherer.held().front().release_at;
  };
  // Every corner of a footprint as far as it reaches: the box's half extents plus `grow`.
  const auto corners_grown = [](const tracking::VehicleHypothesis& v, double grow) {
    std::vector<Eigen::Vector2d> c;
    for (const double sx : {-1.0, 1.0}) {
      for (const double sy : {-1.0, 1.0})
        c.push_back(v.centre +
                    Eigen::Vector2d(sx * (0.5 * v.size.length_m + grow), sy * (0.5 * v.size.width_m + grow)));
    }
    return c;
  };

  tracking::VehicleHypothesis uncertain = car({10.0, -0.5}, 0.0);
  uncertain.covariance = Eigen::Vector3d(0.25, 0.25, 1e-4).asDiagonal();
  const TimeNs tight_passed = sweep.passed_time(corners_grown(uncertain, 0.4 + 0.5));
  const TimeNs grown_passed =
      sweep.passed_time(corners_grown(uncertain, 2.5 * (0.5 + 0.01 * std::hypot(4.6, 1.8) / 2)));
  ASSERT_LT(tight_passed, grown_passed);
  EXPECT_GT(tight_passed, kNow);
  EXPECT_EQ(release_at(uncertain, seen), tight_passed);

  const tracking::VehicleHypothesis certain = car({10.0, -0.5}, 0.0);
  const TimeNs certain_tight = sweep.passed_time(corners_grown(certain, 0.4 + 0.1));
  const TimeNs certain_grown = sweep.passed_time(corners_grown(certain, 0.4));
  ASSERT_LT(certain_grown, certain_tight);
  EXPECT_EQ(release_at(certain, seen), certain_grown);

  perception::Detection neighbour = seen;  // its points 1.4 m off the car's side: outside the tight one
  for (Eigen::Vector3d& p : neighbour.points)
    p.y() += 1.4;
  EXPECT_EQ(release_at(uncertain, neighbour), grown_passed);
}

}  // namespace
}  // namespace rsu::core
