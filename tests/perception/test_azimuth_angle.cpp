// SPDX-License-Identifier: Apache-2.0
// azimuth_angle (azimuth_thinning.h) against the standard library's double atan2: every direction of a
// fine circle, the octants' and the fold's edges (tan(pi/8)), the axes, magnitudes from 1e-300 to 1e300.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "perception/azimuth_thinning.h"

namespace {

using rsu::perception::azimuth_angle;

TEST(AzimuthAngle, MatchesAtan2AroundTheCircle) {
  constexpr int kSteps = 200'003;  // not a multiple of 8: directions fall between the octants' edges
  double worst = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double a = -std::numbers::pi + 2.0 * std::numbers::pi * (i + 0.5) / kSteps;
    for (const double r : {1e-300, 1e-3, 1.0, 37.5, 1e300}) {
      const double y = r * std::sin(a), x = r * std::cos(a);
      worst = std::max(worst, std::abs(azimuth_angle(y, x) - std::atan2(y, x)));
    }
  }
  EXPECT_LT(worst, 1e-10);
}

TEST(AzimuthAngle, EdgesOfTheFold) {
  const double tan_pi_8 = std::tan(std::numbers::pi / 8.0);
  for (const double t : {0.0, std::nextafter(tan_pi_8, 0.0), tan_pi_8, std::nextafter(tan_pi_8, 1.0), 1.0}) {
    for (const double sx : {1.0, -1.0}) {
      for (const double sy : {1.0, -1.0}) {
        EXPECT_NEAR(azimuth_angle(sy * t, sx), std::atan2(sy * t, sx), 1e-10) << t << ' ' << sx << ' ' << sy;
        EXPECT_NEAR(azimuth_angle(sy, sx * t), std::atan2(sy, sx * t), 1e-10) << t << ' ' << sx << ' ' << sy;
      }
    }
  }
}

TEST(AzimuthAngle, Axes) {
  EXPECT_EQ(azimuth_angle(0.0, 0.0), 0.0);
  EXPECT_EQ(azimuth_angle(0.0, 2.0), 0.0);
  EXPECT_NEAR(azimuth_angle(2.0, 0.0), std::numbers::pi / 2.0, 1e-15);
  EXPECT_NEAR(azimuth_angle(-2.0, 0.0), -std::numbers::pi / 2.0, 1e-15);
  EXPECT_NEAR(azimuth_angle(0.0, -2.0), std::numbers::pi, 1e-15);
  EXPECT_NEAR(azimuth_angle(1.0, 1.0), std::numbers::pi / 4.0, 1e-15);
  EXPECT_NEAR(azimuth_angle(-1.0, -1.0), -3.0 * std::numbers::pi / 4.0, 1e-15);
}

}  // namespace
