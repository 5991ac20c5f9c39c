// SPDX-License-Identifier: Apache-2.0
// The least-squares refit of a rectangle's orientation on its seen faces (face_refinement.h), against an
// L of points whose direction the test knows.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "perception/face_refinement.h"
#include "perception/l_shape_fitting.h"

namespace rsu::perception {
namespace {

// A vehicle's near side (4.5 m along x at y = 0) and near end (1.8 m along y at x = 0), every 0.1 m,
// `noise` m across each face (normal, seeded), seen from (-10, -10).
std::vector<Eigen::Vector2d> l_of_points(double noise, std::mt19937& rng) {
  std::normal_distribution<double> across(0.0, noise);
  std::vector<Eigen::Vector2d> points;
  for (double x = 0.05; x < 4.5; x += 0.1)
    points.emplace_back(x, across(rng));
  for (double y = 0.05; y < 1.8; y += 0.1)
    points.emplace_back(across(rng), y);
  return points;
}

const Eigen::Vector2d kLidar(-10.0, -10.0);

// The rectangle bounding `points` along yaw and yaw + pi/2, as a fit at that yaw would give it.
RectangleFit fit_at(const std::vector<Eigen::Vector2d>& points, double yaw) {
  RectangleFit fit;
  fit.status = FitStatus::ok;
  fit.yaw = yaw;
  const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), v(-u.y(), u.x());
  double c1_min = 1e9, c1_max = -1e9, c2_min = 1e9, c2_max = -1e9;
  for (const Eigen::Vector2d& p : points) {
    c1_min = std::min(c1_min, p.dot(u));
    c1_max = std::max(c1_max, p.dot(u));
    c2_min = std::min(c2_min, p.dot(v));
    c2_max = std::max(c2_max, p.dot(v));
  }
  set_rectangle_geometry(fit, Eigen::Vector2d::Zero(), c1_min, c1_max, c2_min, c2_max);
  set_edge_observations(fit, points, kLidar, LShapeFitConfig{});
  return fit;
}

// The orientation error of a rectangle whose faces should run along x and y (mod 90 deg).
double direction_error(const RectangleFit& fit) {
  return std::abs(std::remainder(fit.yaw, std::numbers::pi / 2.0));
}

// Exact points: the refit finds the faces' direction where each face's band holds its own points only.
// Where the fit is far enough off that one face's band reaches the other face's points by the corner, the
// refit is turned by them: 8 deg off, it is 2.8 deg off. (Refitting again on the refit's bands until it
// settles, tried on the pilot matrices, removed two yaw fixes beyond 3 sigma but moved the cells by -0.7
// to +0.4 points under 0.10 m, not kept; how far the refit would move widens its yaw instead:
// refit_unsettled_rad, README, the pilot matrix.)
TEST(FaceRefinement, ExactFacesGiveTheirDirectionUnlessABandHoldsTheOtherFace) {
  std::mt19937 rng(1);
  const std::vector<Eigen::Vector2d> points = l_of_points(0.0, rng);
  for (const double yaw_deg : {-6.0, -2.0, 3.0}) {
    const RectangleFit fit = fit_at(points, deg_to_rad(yaw_deg));
    ASSERT_TRUE(fit.ok());
    EXPECT_LT(direction_error(refine_on_faces(fit, points, kLidar)), 1e-9) << yaw_deg;
  }
  const double off = direction_error(refine_on_faces(fit_at(points, deg_to_rad(8.0)), points, kLidar));
  EXPECT_GT(off, deg_to_rad(1.0));
  EXPECT_LT(off, deg_to_rad(8.0));
}

// Noisy faces (4 cm), the fit 6 deg off: the refit comes nearer the faces' direction, not all the way
// (the support band of a turned edge holds the points that happen to lie near it): 2.4 deg off on average
// over these trials; refitting until it settled, under 1 deg.
TEST(FaceRefinement, NoisyFacesRefitNearer) {
  std::mt19937 rng(7);
  double refit = 0.0;
  constexpr int kTrials = 200;
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::vector<Eigen::Vector2d> points = l_of_points(0.04, rng);
    const RectangleFit fit = fit_at(points, deg_to_rad(trial % 2 == 0 ? 6.0 : -6.0));
    refit += direction_error(refine_on_faces(fit, points, kLidar));
  }
  refit /= kTrials;
  EXPECT_LT(refit, deg_to_rad(6.0) / 2.0);
  EXPECT_GT(refit, deg_to_rad(1.0));
}

// Refit again and again, the refit of an exact L 8 deg off moves by as much as it is off (to the faces'
// own direction); a refit already on the faces' direction does not move.
TEST(FaceRefinement, AnUnsettledRefitSaysHowFarItMoves) {
  std::mt19937 rng(1);
  const std::vector<Eigen::Vector2d> points = l_of_points(0.0, rng);
  const RectangleFit off = refine_on_faces(fit_at(points, deg_to_rad(8.0)), points, kLidar);
  ASSERT_GT(direction_error(off), deg_to_rad(1.0));
  EXPECT_NEAR(refit_unsettled_rad(off, points, kLidar), direction_error(off), 1e-6);
  const RectangleFit on = refine_on_faces(fit_at(points, deg_to_rad(3.0)), points, kLidar);
  EXPECT_LT(refit_unsettled_rad(on, points, kLidar), 1e-9);
  FaceRefinementConfig none;
  none.settle_passes = 0;
  EXPECT_EQ(refit_unsettled_rad(off, points, kLidar, {}, none), 0.0);
}

// A refit more than max_change_rad from the fit is not taken, nor is a fit that is not ok refit.
TEST(FaceRefinement, ATurnBeyondTheLimitKeepsTheFit) {
  std::mt19937 rng(3);
  const std::vector<Eigen::Vector2d> points = l_of_points(0.0, rng);
  const RectangleFit fit = fit_at(points, deg_to_rad(6.0));
  FaceRefinementConfig tight;
  tight.max_change_rad = deg_to_rad(4.0);
  EXPECT_NEAR(refine_on_faces(fit, points, kLidar, {}, tight).yaw, fit.yaw, 1e-12);
  RectangleFit not_ok = fit;
  not_ok.status = FitStatus::degenerate;
  EXPECT_EQ(refine_on_faces(not_ok, points, kLidar).yaw, fit.yaw);
}

}  // namespace
}  // namespace rsu::perception
