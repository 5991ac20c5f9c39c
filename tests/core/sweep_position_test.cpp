// SPDX-License-Identifier: Apache-2.0
// SweepPosition::passed_time against a brute-force walk of the sensor's future firings: the first time
// at which every laser's beam has passed a place far enough that no return there could still join a
// cluster (sweep_clusterer.h's rule), found by stepping the encoder forward.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "common/angles.h"
#include "core/sweep_position.h"

namespace rsu::core {
namespace {

constexpr double kRotationHz = 10.0;
constexpr double kToleranceM = 0.7;
constexpr double kMarginDeg = 0.5;
// Clockwise beam azimuth minus encoder azimuth, per ring: an Ouster-like four-beam stagger.
const std::vector<double> kOffsets = {deg_to_rad(4.2), deg_to_rad(1.4), deg_to_rad(-1.4), deg_to_rad(-4.2)};

lidar::SweepGeometry geometry() {
  lidar::SweepGeometry g;
  g.rotation_hz = kRotationHz;
  g.ring_azimuth_offset_rad = kOffsets;
  return g;
}

// A point on the map at `azimuth` (clockwise from the sensor's +x, the LiDAR at the origin, unturned) and
// planar range `range`.
Eigen::Vector2d at(double azimuth, double range) {
  return {range * std::cos(azimuth), -range * std::sin(azimuth)};
}

// The newest point of the stream: ring `ring` fired at encoder azimuth `encoder`, at time `time`.
lidar::LidarPoint newest(std::uint16_t ring, double encoder, TimeNs time) {
  lidar::LidarPoint p;
  p.ring = ring;
  const double offset = ring < kOffsets.size() ? kOffsets[ring] : 0.0;
  p.azimuth_rad = static_cast<float>(wrap_angle_positive(encoder + offset));
  p.time_ns = time;
  return p;
}

// Brute force: step the encoder on from `encoder` at `time` (1 us steps) until every laser's beam lies
// past the place's azimuth by the closing angle and the margin.
TimeNs brute_force_passed(double place_azimuth, double place_range, double encoder, TimeNs time) {
  const double closing = std::asin(kToleranceM / place_range) + deg_to_rad(kMarginDeg);
  const double radians_per_ns = 2.0 * std::numbers::pi * kRotationHz * 1e-9;
  for (TimeNs t = time;; t += 1000) {
    const double e = encoder + radians_per_ns * static_cast<double>(t - time);
    bool all_past = true;
    for (const double o : kOffsets)
      all_past = all_past && e + o > place_azimuth + closing;
    if (all_past)
      return t;
  }
}

TEST(SweepPosition, PassedWhenTheTrailingLaserHasSweptPastTheNewestPointsEncoder) {
  const LidarMount mount(Pose3{});
  const TimeNs t0 = 5'000'000'000;
  const double place = 1.0;  // rad
  const double range = 10.0;
  // The newest point from each laser in turn, all fired at the same encoder azimuth just past the place:
  // the time the place is passed depends on the encoder only, not on which laser fired last.
  const double encoder = place + deg_to_rad(1.0);
  for (std::uint16_t ring = 0; ring < kOffsets.size(); ++ring) {
    SweepPosition sweep(mount, kToleranceM, kMarginDeg, geometry());
    const lidar::LidarPoint p = newest(ring, encoder, t0);
    sweep.advance(std::span<const lidar::LidarPoint>(&p, 1));
    const std::vector<Eigen::Vector2d> outline = {at(place, range)};
    const TimeNs expected = brute_force_passed(place, range, encoder, t0);
    EXPECT_NEAR(static_cast<double>(sweep.passed_time(outline)), static_cast<double>(expected), 2000.0)
        << "newest point from ring " << ring;
  }
}

TEST(SweepPosition, ALaserOutsideTheTableCountsAsTheLeadingOne) {
  const LidarMount mount(Pose3{});
  const TimeNs t0 = 1'000'000'000;
  const double place = 2.0;
  const double range = 20.0;
  SweepPosition sweep(mount, kToleranceM, kMarginDeg, geometry());
  // Ring 9 is not in the table: its beam azimuth is taken as the leading laser's, so the encoder may be
  // as far back as that azimuth minus the largest offset.
  lidar::LidarPoint p = newest(0, place, t0);
  p.ring = 9;
  sweep.advance(std::span<const lidar::LidarPoint>(&p, 1));
  const std::vector<Eigen::Vector2d> outline = {at(place, range)};
  const TimeNs expected = brute_force_passed(place, range, place, t0);  // encoder = beam azimuth - 4.2 deg
  EXPECT_NEAR(static_cast<double>(sweep.passed_time(outline)), static_cast<double>(expected), 2000.0);
}

// swept(): every laser's beam past every point of the outline by the margin (no closing angle: the
// early release of prepared_fixes.h asks whether a return from inside it can still come), against the
// brute-force walk with the closing angle left out: swept exactly when the walk ends at once.
TEST(SweepPosition, SweptOnceEveryLaserHasPassedEveryPointOfTheOutline) {
  const LidarMount mount(Pose3{});
  const TimeNs t0 = 5'000'000'000;
  const double place = 1.0;  // the outline's largest azimuth; its other corner 2 deg before, nearer
  const std::vector<Eigen::Vector2d> outline = {at(place - deg_to_rad(2.0), 4.0), at(place, 6.0)};
  const double radians_per_ns = 2.0 * std::numbers::pi * kRotationHz * 1e-9;
  int swept = 0;
  for (double beyond_deg = -3.1; beyond_deg < 14.0; beyond_deg += 0.25) {
    for (std::uint16_t ring = 0; ring < kOffsets.size(); ++ring) {
      SweepPosition sweep(mount, kToleranceM, kMarginDeg, geometry());
      EXPECT_FALSE(sweep.swept(outline)) << "the sweep is not known yet";
      const double encoder = place + deg_to_rad(beyond_deg);
      const lidar::LidarPoint p = newest(ring, encoder, t0);
      sweep.advance(std::span<const lidar::LidarPoint>(&p, 1));
      bool every_laser_past = true;
      for (const double o : kOffsets)
        every_laser_past = every_laser_past && encoder + o > place + deg_to_rad(kMarginDeg);
      EXPECT_EQ(sweep.swept(outline), every_laser_past) << beyond_deg << " deg, ring " << ring;
      EXPECT_FALSE(sweep.swept({})) << "an empty outline";
      swept += every_laser_past ? 1 : 0;
      // Swept is passed_time without the closing angle: no later than it.
      if (every_laser_past) {
        EXPECT_GE(sweep.passed_time(outline), t0);
      } else {
        const double to_go = place + deg_to_rad(kMarginDeg) - kOffsets.back() - encoder;
        EXPECT_GT(static_cast<double>(sweep.passed_time(outline) - t0), to_go / radians_per_ns - 2000.0);
      }
    }
  }
  EXPECT_GT(swept, 20);
  EXPECT_LT(swept, 68 * 4 - 20);
}

}  // namespace
}  // namespace rsu::core
