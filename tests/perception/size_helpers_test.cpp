// SPDX-License-Identifier: Apache-2.0
// The size correction's small rules (size_correction.h: which sizes are valid, up to which heights a
// point is on the lower body, the ends, surely the bonnet), the per-point noise of the covariance model
// (fix_covariance.h) and what a LiDAR's lasers see (lidar_geometry.h), each against numbers worked out
// in the test from the contract in the header.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/angles.h"
#include "perception/fix_covariance.h"
#include "perception/lidar_geometry.h"
#include "perception/size_correction.h"

namespace rsu::perception {
namespace size_helpers_test {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

TEST(SizeCorrectionRules, ValidSizeIsFinitePositiveLengthAndWidth) {
  EXPECT_TRUE(valid_size({4.89, 1.92, 1.70}));
  EXPECT_TRUE(valid_size({0.01, 0.01, 1.0}));
  // The height is not judged: unknown or nonsense, the footprint is still valid.
  EXPECT_TRUE(valid_size({4.0, 1.8, kNan}));
  EXPECT_TRUE(valid_size({4.0, 1.8, -1.0}));
  for (const VehicleSize bad :
       {VehicleSize{0.0, 1.8, 1.5}, VehicleSize{4.0, 0.0, 1.5}, VehicleSize{-4.0, 1.8, 1.5},
        VehicleSize{4.0, -1.8, 1.5}, VehicleSize{kNan, 1.8, 1.5}, VehicleSize{4.0, kNan, 1.5},
        VehicleSize{kInf, 1.8, 1.5}, VehicleSize{4.0, kInf, 1.5}}) {
    EXPECT_FALSE(valid_size(bad)) << bad.length << " x " << bad.width;
  }
}

// lower_body_fraction (0.55) of the height; every point (infinity) when the height is unknown.
TEST(SizeCorrectionRules, LowerBodyIsItsShareOfTheAnnouncedHeight) {
  const CorrectionConfig config;
  EXPECT_NEAR(lower_body_height({4.89, 1.92, 1.70}, config), 0.935, 1e-12);  // 0.55 x 1.70
  EXPECT_NEAR(lower_body_height({12.0, 2.5, 3.20}, config), 1.76, 1e-12);    // 0.55 x 3.20
  for (const double h : {0.0, -1.0, kNan, kInf})
    EXPECT_EQ(lower_body_height({4.0, 1.8, h}, config), kInf) << h;
  CorrectionConfig half;
  half.lower_body_fraction = 0.5;
  EXPECT_NEAR(lower_body_height({4.0, 1.8, 1.5}, half), 0.75, 1e-12);
}

// min(lower body, max_end_body_height_m = 1.0); every point when the height is unknown.
TEST(SizeCorrectionRules, EndBodyIsTheLowerBodyUpToTheBonnetCap) {
  const CorrectionConfig config;
  EXPECT_NEAR(end_body_height({4.89, 1.92, 1.70}, config), 0.935, 1e-12);  // 0.935 < 1.0
  EXPECT_NEAR(end_body_height({12.0, 2.5, 3.20}, config), 1.0, 1e-12);     // 1.76 capped
  EXPECT_NEAR(end_body_height({5.0, 2.0, 2.45}, config), 1.0, 1e-12);      // a van: 1.3475 capped
  EXPECT_EQ(end_body_height({4.0, 1.8, kNan}, config), kInf);
  EXPECT_EQ(end_body_height({4.0, 1.8, 0.0}, config), kInf);
}

// max(lower body, full_plan_height_m = 0.9).
TEST(SizeCorrectionRules, SideBodyReachesTheFullPlanOnASmallCar) {
  const CorrectionConfig config;
  EXPECT_NEAR(side_body_height({3.4, 1.48, 1.48}, config), 0.9, 1e-12);     // 0.814 < 0.9
  EXPECT_NEAR(side_body_height({4.89, 1.92, 1.70}, config), 0.935, 1e-12);  // 0.935 > 0.9
  EXPECT_EQ(side_body_height({4.0, 1.8, kNan}, config), kInf);
}

// Below max_end_body_height_m (1.0): min(end height, min_bonnet_height_m = 0.8); at or above it, itself.
TEST(SizeCorrectionRules, SurelyBonnetHighIsTheBonnetFloorOnCarsOnly) {
  const CorrectionConfig config;
  EXPECT_NEAR(surely_bonnet_high(0.935, config), 0.8, 1e-12);  // the SUV: its bonnet may be at 0.8
  EXPECT_NEAR(surely_bonnet_high(0.7, config), 0.7, 1e-12);    // lower than the floor: itself
  EXPECT_NEAR(surely_bonnet_high(0.8, config), 0.8, 1e-12);
  EXPECT_NEAR(surely_bonnet_high(1.0, config), 1.0, 1e-12);  // at the cap: a van or bus, all of it
  EXPECT_NEAR(surely_bonnet_high(1.2, config), 1.2, 1e-12);
  EXPECT_EQ(surely_bonnet_high(kInf, config), kInf);  // height unknown: every point
  // Chained: a car's end height gives the floor, a bus's the cap.
  EXPECT_NEAR(surely_bonnet_high(end_body_height({4.89, 1.92, 1.70}, config), config), 0.8, 1e-12);
  EXPECT_NEAR(surely_bonnet_high(end_body_height({12.0, 2.5, 3.2}, config), config), 1.0, 1e-12);
}

// sigma_n^2 = sigma_range^2 + (R sigma_angle)^2 (fix_covariance.h, Model).
TEST(PointNoiseVariance, IsRangeNoisePlusAngleNoiseAtTheRange) {
  const CovarianceModelConfig config;                                       // 0.02 m, 0.001 rad
  EXPECT_NEAR(point_noise_variance(0.0, config), 0.0004, 1e-15);            // 0.02^2
  EXPECT_NEAR(point_noise_variance(30.0, config), 0.0004 + 0.0009, 1e-15);  // + (30 x 0.001)^2
  EXPECT_NEAR(point_noise_variance(100.0, config), 0.0004 + 0.01, 1e-15);
  CovarianceModelConfig other;
  other.range_sigma_m = 0.03;
  other.angle_sigma_rad = 0.002;
  EXPECT_NEAR(point_noise_variance(50.0, other), 0.0009 + 0.01, 1e-15);  // 0.03^2 + (50 x 0.002)^2
}

TEST(PointNoiseVariance, GrowsStrictlyWithRange) {
  const CovarianceModelConfig config;
  double previous = point_noise_variance(0.0, config);
  for (double r = 0.5; r <= 300.0; r += 0.5) {
    const double v = point_noise_variance(r, config);
    EXPECT_GT(v, previous) << r;
    previous = v;
  }
}

// A negative range counts as 0 (the range noise alone); an unknown one bounds nothing: infinite, never NaN
// and never the smallest noise.
TEST(PointNoiseVariance, NegativeRangeCountsAsZeroUnknownRangeAsUnbounded) {
  const CovarianceModelConfig config;
  EXPECT_EQ(point_noise_variance(-5.0, config), point_noise_variance(0.0, config));
  for (const double r : {kNan, std::numeric_limits<double>::infinity()}) {
    const double v = point_noise_variance(r, config);
    EXPECT_TRUE(std::isinf(v) && v > 0.0) << r;
  }
}

LidarGeometry mast(double z, double ground_z) {
  LidarGeometry g;
  g.position = Eigen::Vector3d(3.0, -2.0, z);
  g.ground_z = ground_z;
  g.elevations_rad = {deg_to_rad(-15.0), deg_to_rad(-10.0), deg_to_rad(0.0)};
  return g;
}

TEST(LidarGeometrySurface, HeightAboveGroundIsPositionMinusRoad) {
  EXPECT_DOUBLE_EQ(mast(5.0, 0.0).height_above_ground(), 5.0);
  EXPECT_DOUBLE_EQ(mast(105.0, 101.5).height_above_ground(), 3.5);
  EXPECT_DOUBLE_EQ(mast(-1.0, -3.0).height_above_ground(), 2.0);
}

// A LiDAR 5 m above the road with lasers at -15, -10 and 0 deg. At 20 m their cones cross a vertical
// surface at 5 + 20 tan(e): -15 deg: 5 - 5.359 = -0.359 (below the road), -10 deg: 5 - 3.527 = 1.473,
// 0 deg: 5.
TEST(LidarGeometrySurface, SeesASurfaceWhereALaserCrossesIt) {
  const LidarGeometry g = mast(5.0, 0.0);
  EXPECT_TRUE(g.sees_surface(20.0, 0.5, 1.5));   // 1.473 within
  EXPECT_FALSE(g.sees_surface(20.0, 1.5, 4.9));  // between the -10 and 0 deg cones
  EXPECT_TRUE(g.sees_surface(20.0, 4.9, 5.1));   // the 0 deg laser
  EXPECT_FALSE(g.sees_surface(20.0, 0.0, 1.4));  // the -15 deg laser hits the road before
  // At 10 m: -15 deg at 5 - 2.679 = 2.321, -10 deg at 5 - 1.763 = 3.237.
  EXPECT_TRUE(g.sees_surface(10.0, 2.0, 2.5));
  EXPECT_FALSE(g.sees_surface(10.0, 0.0, 2.2));
  // The road's height moves the crossings: ground at 1 m, the LiDAR 4 m above it: -10 deg at 20 m is
  // 4 - 3.527 = 0.473 above the road.
  const LidarGeometry raised_road = mast(5.0, 1.0);
  EXPECT_TRUE(raised_road.sees_surface(20.0, 0.4, 0.5));
  EXPECT_FALSE(raised_road.sees_surface(20.0, 1.4, 1.5));
}

TEST(LidarGeometrySurface, NoRangeSeesNothingUnknownLasersSeeEverything) {
  const LidarGeometry g = mast(5.0, 0.0);
  for (const double r : {0.0, -3.0, kNan})
    EXPECT_FALSE(g.sees_surface(r, -100.0, 100.0)) << r;
  LidarGeometry unknown = g;
  unknown.elevations_rad.clear();
  EXPECT_TRUE(unknown.sees_surface(20.0, 1.5, 4.9));
  EXPECT_TRUE(unknown.sees_surface(0.0, 1.5, 1.6));
}

}  // namespace size_helpers_test
}  // namespace rsu::perception
