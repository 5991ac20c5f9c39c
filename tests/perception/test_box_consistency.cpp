// SPDX-License-Identifier: Apache-2.0
// How well a box of known size holds a vehicle's points (box_consistency.h): points placed at known
// distances outside it, and faces the LiDAR should have seen covered or not. The expected shares are
// written from the header's definitions (the outline in bins, each weighted by the cosine of incidence at
// its centre), not taken from the function.
#include "perception/box_consistency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

const Eigen::Vector2d kCentre(0.0, 0.0);
const Eigen::Vector2d kHalf(2.0, 1.0);  // a 4 x 2 m box

TEST(BoxConsistency, OutsideFractionCountsPointsBeyondTheTolerance) {
  std::vector<Eigen::Vector2d> points = {
      {0.0, 0.0},  {1.9, 0.9},   {-2.0, 1.0},  // inside, on the corner
      {2.05, 0.0}, {0.0, -1.09},               // outside by less than the tolerance (0.1)
      {2.3, 0.0},  {0.0, 1.5},                 // outside by 0.3 and 0.5 across one face
      {2.2, 1.2},                              // beyond a corner by 0.2 on both axes
  };
  EXPECT_DOUBLE_EQ(outside_fraction(points, kCentre, kHalf, 0.1), 3.0 / 8.0);
  EXPECT_DOUBLE_EQ(outside_fraction(points, kCentre, kHalf, 0.25), 2.0 / 8.0);  // 0.3 and 0.5 only
  EXPECT_DOUBLE_EQ(outside_fraction(points, kCentre, kHalf, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(outside_fraction({}, kCentre, kHalf, 0.1), 0.0);
  // The box may sit anywhere: the same points and box moved together.
  const Eigen::Vector2d shift(-7.0, 12.5);
  for (auto& p : points)
    p += shift;
  EXPECT_DOUBLE_EQ(outside_fraction(points, kCentre + shift, kHalf, 0.1), 3.0 / 8.0);
}

// The LiDAR-facing outline's weight by the header's definition: the faces whose outward side the LiDAR is
// on, in bins of face_bin_m, each weighed by the cosine of incidence at its centre (under
// min_incidence_cos: not expected). Returns the weight of the faces on axis `only_axis` (-1: all).
double facing_weight(const Eigen::Vector2d& lidar, const CorrectionConfig& config, int only_axis) {
  double total = 0.0;
  for (int a = 0; a < 2; ++a) {
    for (const double side : {-1.0, 1.0}) {
      const double face = kCentre[a] + side * kHalf[a];
      const double towards = side * (lidar[a] - face);
      if (towards <= 0.0 || (only_axis >= 0 && a != only_axis))
        continue;
      const int b = 1 - a;
      const double length = 2.0 * kHalf[b];
      const int bins = static_cast<int>(std::ceil(length / config.face_bin_m));
      for (int j = 0; j < bins; ++j) {
        const double t = kCentre[b] - kHalf[b] + (j + 0.5) * length / bins;
        const double cos_incidence = towards / std::hypot(towards, lidar[b] - t);
        if (cos_incidence >= config.min_incidence_cos)
          total += cos_incidence;
      }
    }
  }
  return total;
}

// Points along a face every `spacing`, from 0.2 m inside its ends: farther than the cover radius (0.15 m)
// from the faces they meet, so each covers only its own face (to its ends, 0.15 m on either side).
std::vector<Eigen::Vector2d> face_points(int axis, double side, double spacing) {
  std::vector<Eigen::Vector2d> out;
  const int b = 1 - axis;
  for (double t = -kHalf[b] + 0.2; t <= kHalf[b] - 0.2 + 1e-9; t += spacing) {
    Eigen::Vector2d p;
    p[axis] = side * kHalf[axis];
    p[b] = t;
    out.push_back(p);
  }
  return out;
}

TEST(BoxConsistency, InconsistencyIsOutsideShareAndUncoveredFacingOutline) {
  const CorrectionConfig config;
  const Eigen::Vector2d lidar(10.0, -6.0);  // sees the +x end and the -y side
  const std::vector<Eigen::Vector2d> end = face_points(0, 1.0, 0.05);
  const std::vector<Eigen::Vector2d> side = face_points(1, -1.0, 0.05);
  std::vector<Eigen::Vector2d> both = end;
  both.insert(both.end(), side.begin(), side.end());

  // Both facing faces covered, nothing outside: consistent.
  EXPECT_NEAR(box_inconsistency(both, lidar, kCentre, kHalf, config.cover_radius_m, config), 0.0, 1e-12);
  // Only the side: the end's share of the facing outline is uncovered.
  const double end_share = facing_weight(lidar, config, 0) / facing_weight(lidar, config, -1);
  EXPECT_GT(end_share, 0.1);
  EXPECT_LT(end_share, 0.9);
  EXPECT_NEAR(box_inconsistency(side, lidar, kCentre, kHalf, config.cover_radius_m, config), end_share,
              1e-12);
  EXPECT_NEAR(box_inconsistency(end, lidar, kCentre, kHalf, config.cover_radius_m, config), 1.0 - end_share,
              1e-12);
  // The far faces (+y side, -x end) are not expected: points only there leave the facing outline bare.
  std::vector<Eigen::Vector2d> far = face_points(1, 1.0, 0.05);
  const std::vector<Eigen::Vector2d> far_end = face_points(0, -1.0, 0.05);
  far.insert(far.end(), far_end.begin(), far_end.end());
  EXPECT_NEAR(box_inconsistency(far, lidar, kCentre, kHalf, config.cover_radius_m, config), 1.0, 1e-12);
  // A quarter of the points 0.5 m outside adds their share.
  std::vector<Eigen::Vector2d> with_outside = both;
  const std::size_t n = with_outside.size();
  for (std::size_t i = 0; i < n / 3; ++i)
    with_outside.emplace_back(0.0, 1.5);
  const double share = static_cast<double>(n / 3) / static_cast<double>(with_outside.size());
  EXPECT_NEAR(box_inconsistency(with_outside, lidar, kCentre, kHalf, config.cover_radius_m, config), share,
              1e-12);
}

TEST(BoxConsistency, BoundsOfTheScale) {
  const CorrectionConfig config;
  const Eigen::Vector2d lidar(10.0, -6.0);
  // No points: the whole facing outline uncovered, nothing outside.
  EXPECT_DOUBLE_EQ(box_inconsistency({}, lidar, kCentre, kHalf, config.cover_radius_m, config), 1.0);
  // Every point far outside: both terms at their maximum.
  const std::vector<Eigen::Vector2d> away = {{20.0, 20.0}, {-30.0, 5.0}};
  EXPECT_DOUBLE_EQ(box_inconsistency(away, lidar, kCentre, kHalf, config.cover_radius_m, config), 2.0);
  // A LiDAR inside the box faces no face: nothing is expected, which counts as uncovered.
  const std::vector<Eigen::Vector2d> end = face_points(0, 1.0, 0.05);
  EXPECT_DOUBLE_EQ(box_inconsistency(end, {0.5, 0.0}, kCentre, kHalf, config.cover_radius_m, config), 1.0);
  // A face seen exactly edge-on (the LiDAR on its line) is not expected: seen from (10, -1), straight down
  // the -y side's line, the +x end alone is the facing outline.
  EXPECT_NEAR(box_inconsistency(end, {10.0, -1.0}, kCentre, kHalf, config.cover_radius_m, config), 0.0,
              1e-12);
}

}  // namespace
}  // namespace rsu::perception
