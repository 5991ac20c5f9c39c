// SPDX-License-Identifier: Apache-2.0
// LidarGeometry's occlusion test and its log: which other objects' points hide a place from the LiDAR, and
// when another set of points answers the same questions (what lets a fix prepared before the sweep's other
// objects were complete stand at the release, core/prepared_fixes.h).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "perception/lidar_geometry.h"

namespace rsu::perception {
namespace {

LidarGeometry lidar_at_origin() {
  LidarGeometry lidar;
  lidar.position = Eigen::Vector3d(0.0, 0.0, 2.0);
  lidar.azimuth_step_rad = deg_to_rad(0.2);
  return lidar;
}

// The rule written out independently: an occluder hides `xy` when it lies nearer than xy by more than
// the margin and within the larger of two azimuth steps and the angle the margin subtends at xy's range.
bool hides(const Eigen::Vector2d& occluder, const Eigen::Vector2d& xy, double margin, double step_rad) {
  const double range = xy.norm();
  const double r = occluder.norm();
  const double angle = std::abs(std::atan2(occluder.y(), occluder.x()) - std::atan2(xy.y(), xy.x()));
  return r > 0.0 && r < range - margin && angle <= std::max(2.0 * step_rad, std::atan(margin / range));
}

TEST(LidarGeometryOcclusion, NearerPointsWithinTheMarginsAngleHide) {
  LidarGeometry lidar = lidar_at_origin();
  const Eigen::Vector2d place(10.0, 0.0);
  const double margin = 0.3;  // subtends 1.72 deg at 10 m, more than two azimuth steps (0.4 deg)
  const std::vector<Eigen::Vector2d> candidates = {
      {5.0, 0.05},  // 0.57 deg off the line of sight, half way: hides
      {5.0, 0.14},  // 1.60 deg: hides
      {5.0, 0.16},  // 1.83 deg: beside it
      {9.8, 0.0},   // on the line of sight, but within the margin of the place: the place's own body
      {12.0, 0.0},  // behind it
      {-5.0, 0.0},  // the other way
  };
  for (const Eigen::Vector2d& c : candidates) {
    lidar.occluders = {c};
    EXPECT_EQ(lidar.occluded(place, margin), hides(c, place, margin, lidar.azimuth_step_rad))
        << c.transpose();
  }
  EXPECT_TRUE(hides(candidates[0], place, margin, lidar.azimuth_step_rad));
  EXPECT_FALSE(hides(candidates[2], place, margin, lidar.azimuth_step_rad));
  // Far out the margin subtends less than two azimuth steps: those bound it (0.4 deg at 60 m is 0.42 m).
  lidar.occluders = {{30.0, 0.18}};  // 0.34 deg
  EXPECT_TRUE(lidar.occluded({60.0, 0.0}, margin));
  lidar.occluders = {{30.0, 0.24}};  // 0.46 deg
  EXPECT_FALSE(lidar.occluded({60.0, 0.0}, margin));
  lidar.occluders.clear();
  EXPECT_FALSE(lidar.occluded(place, margin));
}

TEST(LidarGeometryOcclusion, LogRecordsEachQuestionAndItsAnswer) {
  LidarGeometry lidar = lidar_at_origin();
  lidar.occluders = {{5.0, 0.05}, {3.0, 4.0}};
  std::vector<OcclusionQuery> log;
  lidar.occluded({10.0, 0.0}, 0.3);  // no log yet: nothing recorded
  lidar.occlusion_log = &log;
  const bool a = lidar.occluded({10.0, 0.0}, 0.3);
  const bool b = lidar.occluded({0.0, 10.0}, 0.3);
  const bool c = lidar.occluded({6.0, 8.0}, 0.3);  // behind (3, 4)
  ASSERT_EQ(log.size(), 3U);
  EXPECT_TRUE(a);
  EXPECT_FALSE(b);
  EXPECT_TRUE(c);
  EXPECT_EQ(log[0].xy, Eigen::Vector2d(10.0, 0.0));
  EXPECT_EQ(log[1].xy, Eigen::Vector2d(0.0, 10.0));
  EXPECT_EQ(log[2].margin, 0.3);
  EXPECT_EQ(log[0].occluded, a);
  EXPECT_EQ(log[1].occluded, b);
  EXPECT_EQ(log[2].occluded, c);
}

// Other occluders answer alike exactly when every recorded question gets its recorded answer: points
// added where no question looked change nothing; one that hides a place that was clear, or one taken
// away that hid a place, does.
TEST(LidarGeometryOcclusion, OtherOccludersAnswerAlikeWhenNoQuestionTurns) {
  LidarGeometry lidar = lidar_at_origin();
  lidar.occluders = {{5.0, 0.05}};
  std::vector<OcclusionQuery> log;
  lidar.occlusion_log = &log;
  ASSERT_TRUE(lidar.occluded({10.0, 0.0}, 0.3));
  ASSERT_FALSE(lidar.occluded({0.0, 10.0}, 0.3));

  std::vector<Eigen::Vector2d> grown = lidar.occluders;
  for (int i = 0; i < 50; ++i)  // a passing car's points, swept later, 30-40 deg from either place
    grown.emplace_back(6.0 + 0.02 * i, 4.0);
  EXPECT_TRUE(lidar.answers_alike(grown, log));
  EXPECT_TRUE(lidar.answers_alike(lidar.occluders, log));

  std::vector<Eigen::Vector2d> hiding_the_clear_place = grown;
  hiding_the_clear_place.emplace_back(0.1, 6.0);
  EXPECT_FALSE(lidar.answers_alike(hiding_the_clear_place, log));

  const std::vector<Eigen::Vector2d> without_the_one_that_hid(grown.begin() + 1, grown.end());
  EXPECT_FALSE(lidar.answers_alike(without_the_one_that_hid, log));
  EXPECT_FALSE(lidar.answers_alike({}, log));
  EXPECT_TRUE(lidar.answers_alike({}, {}));  // a fix that asked nothing holds with any occluders
}

}  // namespace
}  // namespace rsu::perception
