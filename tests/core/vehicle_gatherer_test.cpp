// SPDX-License-Identifier: Apache-2.0
// The grown footprint's overlap with a box against an independent test (corners inside, edges
// crossing), and the gatherer's hold for a farther cluster still open where the vehicle may be
// (perception::SweptCluster::open_beyond; issue 16).
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

// A car 10 m east of the LiDAR, its cluster closed and assigned to it, tightly inside its footprint. Alone
// it is released at once; with a farther cluster still open inside its footprint (its own roof seen from
// high up) it is held until the sweep has passed the grown footprint; with one open 3 m beyond it
// (another car passing behind it) it is released at once.
TEST(VehicleGatherer, HoldsForAFartherOpenClusterOnlyWhereTheVehicleMayBe) {
  const LidarMount mount(Pose3{});
  lidar::SweepGeometry geometry;
  geometry.rotation_hz = 10.0;
  geometry.ring_azimuth_offset_rad = {0.0};
  SweepPosition sweep(mount, 0.7, 0.5, geometry);
  const TimeNs now = 2'000'000'000;
  lidar::LidarPoint newest;
  newest.azimuth_rad = static_cast<float>(std::atan2(3.0, 10.0));  // clockwise: just past the car at y < 0
  newest.time_ns = now;
  sweep.advance(std::span<const lidar::LidarPoint>(&newest, 1));
  const tracking::VehicleHypothesis vehicle = car({10.0, -0.5}, 0.0);
  perception::Detection own;
  own.sweep_time_ns = now - 1'000'000;
  for (double x = 8.0; x <= 12.0; x += 0.1)
    own.points.emplace_back(x, 0.35, 0.8);  // its near side
  tracking::AssociationResult association;
  association.pairs.push_back({0, 0, 0.5});
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
  EXPECT_GT(held, now);
  const GrownFootprint footprint(vehicle, GatheringConfig{});
  EXPECT_EQ(held, sweep.passed_time(footprint.corners()));
  const Eigen::AlignedBox2d behind(Eigen::Vector2d(8.0, -6.0), Eigen::Vector2d(12.0, -4.5));
  EXPECT_FALSE(footprint.tightly_overlaps(behind));
  EXPECT_EQ(release_at({behind}), own.sweep_time_ns);
}

}  // namespace
}  // namespace rsu::core
