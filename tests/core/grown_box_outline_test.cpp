// SPDX-License-Identifier: Apache-2.0
// grown_box_outline (core/prepared_fixes.h): the fixed box a cluster released open waits for the sweep to
// pass, against its definition written out here: the announced rectangle at the fix's pose, each side
// moved out by 3 sigma of a corner's displacement (the position covariance's larger axis, from the 2 x 2
// eigenvalue formula, and the yaw sigma times the half diagonal, independent).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/prepared_fixes.h"

namespace rsu::core {
namespace {

double larger_axis_sigma(double xx, double xy, double yy) {
  const double mean = 0.5 * (xx + yy);
  return std::sqrt(mean + std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy));
}

TEST(GrownBoxOutline, EachSideMovesOutByThreeSigmaOfACornersDisplacement) {
  struct Case {
    double x, y, yaw, xx, xy, yy, yaw_var, length, width;
  };
  const Case cases[] = {
      {10.0, -3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.89, 1.92},          // exact: the box itself
      {-4.0, 7.5, 0.7, 0.01, 0.0, 0.0025, 0.0, 4.6, 1.85},        // position only, axis-aligned
      {2.0, 2.0, -2.4, 0.004, 0.003, 0.009, 0.0001, 12.0, 2.55},  // correlated, with yaw: a bus
      {0.0, 0.0, 3.1, 0.0, 0.0, 0.0, 0.0004, 3.6, 1.6},           // yaw only
  };
  for (const Case& c : cases) {
    perception::CorrectedPose fix;
    fix.status = perception::CorrectionStatus::ok;
    fix.pose = {c.x, c.y, c.yaw};
    fix.covariance << c.xx, c.xy, 0.0, c.xy, c.yy, 0.0, 0.0, 0.0, c.yaw_var;
    const double half_diagonal = 0.5 * std::hypot(c.length, c.width);
    const double grow = 3.0 * std::sqrt(std::pow(larger_axis_sigma(c.xx, c.xy, c.yy), 2) +
                                        c.yaw_var * half_diagonal * half_diagonal);
    const auto corners = grown_box_outline(fix, c.length, c.width);
    // In the box's own frame every corner lies at (+-(L/2 + grow), +-(W/2 + grow)), one in each quadrant.
    int quadrants = 0;
    for (const Eigen::Vector2d& corner : corners) {
      const Eigen::Vector2d d = corner - Eigen::Vector2d(c.x, c.y);
      const double along = d.x() * std::cos(c.yaw) + d.y() * std::sin(c.yaw);
      const double across = -d.x() * std::sin(c.yaw) + d.y() * std::cos(c.yaw);
      EXPECT_NEAR(std::abs(along), 0.5 * c.length + grow, 1e-9);
      EXPECT_NEAR(std::abs(across), 0.5 * c.width + grow, 1e-9);
      quadrants |= 1 << ((along > 0 ? 1 : 0) + (across > 0 ? 2 : 0));
    }
    EXPECT_EQ(quadrants, 0b1111) << "a corner in each quadrant";
    // In order around the box: consecutive corners share a side (its length or its width, grown).
    for (std::size_t i = 0; i < 4; ++i) {
      const double side = (corners[(i + 1) % 4] - corners[i]).norm();
      EXPECT_TRUE(std::abs(side - (c.length + 2 * grow)) < 1e-9 ||
                  std::abs(side - (c.width + 2 * grow)) < 1e-9)
          << "side " << i << ": " << side;
    }
  }
}

}  // namespace
}  // namespace rsu::core
