// SPDX-License-Identifier: Apache-2.0
// The L-shape criteria (l_shape_criteria.h) on point sets of a few points whose values are worked out by
// hand in the comments, and the orientation search (orientation_search.h) on rectangles of known
// direction: the criterion's maximum is the rectangle's direction modulo 90 deg.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/angles.h"
#include "perception/l_shape_criteria.h"
#include "perception/orientation_search.h"

namespace rsu::perception {
namespace criteria_direct_test {

struct Points {
  std::vector<double> x, y;
  void add(double px, double py) {
    x.push_back(px);
    y.push_back(py);
  }
};

// An L along the bottom (y = 0) and left (x = 0) edges of the 2 x 1 rectangle [0, 2] x [0, 1], and one
// point inside it at (1, 0.5).
Points bottom_left_l() {
  Points p;
  const double xy[6][2] = {{0.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}, {0.0, 0.5}, {0.0, 1.0}, {1.0, 0.5}};
  for (const auto& q : xy)
    p.add(q[0], q[1]);
  return p;
}

// p rotated by phi about the origin.
Points rotated(const Points& p, double phi) {
  Points out;
  for (std::size_t i = 0; i < p.x.size(); ++i)
    out.add(std::cos(phi) * p.x[i] - std::sin(phi) * p.y[i], std::sin(phi) * p.x[i] + std::cos(phi) * p.y[i]);
  return out;
}

double criterion_at(const Points& p, LShapeCriterion which, double theta, CriterionConfig config = {}) {
  config.criterion = which;
  CriterionEvaluator evaluate(p.x, p.y, config);
  return evaluate(theta);
}

// theta = 0: D1 = x - 0 (mean x = 4/6 lies below the middle, 1: the points are along the min edge) and
// D2 = y - 0 (mean 1/6 < 0.5). Each point scores 1 / max(min(D1, D2), d0): the five on the L have
// min 0 -> 1 / 0.01 = 100 each, the inner point min(1, 0.5) = 0.5 -> 2. Sum 502.
TEST(LShapeCriteria, ZhangClosenessOfAnLWorkedByHand) {
  const Points p = bottom_left_l();
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::closeness, 0.0), 502.0, 502.0 * 1e-5);
  // d0 = 0.1: 5 x 10 + 2 = 52.
  CriterionConfig config;
  config.closeness_d0_m = 0.1;
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::closeness, 0.0, config), 52.0, 52.0 * 1e-5);
  // Period pi / 2: at 90 deg the directions swap (c1 = y, c2 = -x), the rectangle is the same.
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::closeness, kPi / 2.0), 502.0, 502.0 * 1e-4);
}

// The L mirrored through the rectangle's centre (x -> 2 - x, y -> 1 - y) lies along the max edges: the
// criterion must measure from those (mean x = 8/6 > 1), the same 502.
TEST(LShapeCriteria, ZhangClosenessMeasuresFromTheEdgeThePointsLieAlong) {
  const Points l = bottom_left_l();
  Points mirrored;
  for (std::size_t i = 0; i < l.x.size(); ++i)
    mirrored.add(2.0 - l.x[i], 1.0 - l.y[i]);
  EXPECT_NEAR(criterion_at(mirrored, LShapeCriterion::closeness, 0.0), 502.0, 502.0 * 1e-5);
}

// e1 = (cos, sin): the L turned by 0.3 rad scores at theta = 0.3 what the upright one scores at 0, and
// far less at theta = -0.3 (turned the wrong way its points no longer lie on the bounding edges).
TEST(LShapeCriteria, ProjectsOnTheDirectionTheta) {
  const Points p = rotated(bottom_left_l(), 0.3);
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::closeness, 0.3), 502.0, 502.0 * 1e-3);
  EXPECT_LT(criterion_at(p, LShapeCriterion::closeness, -0.3), 0.5 * 502.0);
  // Area: minus the 2 x 1 rectangle's area where it is aligned.
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::area, 0.3), -2.0, 1e-5);
  // At theta = 0, the turned points' bounding box (c = cos 0.3, s = sin 0.3): x = c px - s py ranges
  // from -s (the point (0, 1)) to 2c (the point (2, 0)); y = s px + c py from 0 (the origin) to c (the
  // point (0, 1); 2s = 0.59 and s + c / 2 = 0.77 are less). Area (2c + s) c.
  const double c = std::cos(0.3), s = std::sin(0.3);
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::area, 0.0), -(2.0 * c + s) * c, 1e-5);
}

// theta = 0, D1 = x, D2 = y (as above). E1 = {D1 : D1 < D2}: (0, 0.5) and (0, 1) give 0, 0; E2 = {D2 :
// D2 < D1}: (1, 0), (2, 0) give 0, 0 and (1, 0.5) gives 0.5; (0, 0) is a tie, in neither. var(E1) = 0,
// var(E2) = mean(0, 0, 0.25) - mean(0, 0, 0.5)^2 = 1/12 - 1/36 = 1/18. Criterion -1/18.
TEST(LShapeCriteria, VarianceOfAnLWorkedByHand) {
  EXPECT_NEAR(criterion_at(bottom_left_l(), LShapeCriterion::variance, 0.0), -1.0 / 18.0, 1e-6);
}

// Autoware: each point's element-wise nearer edge, d = min(v1^2, v2^2) with v1 = min(2 - x, x),
// v2 = min(1 - y, y); scored 1 / max(d, 0.01) when d <= 0.4^2 = 0.16, else 0.
//   the five L points: d = 0 -> 1 / 0.01 = 100 each (500)
//   (1, 0.5): v1 = 1, v2 = 0.5, d = 0.25 > 0.16 -> ignored
//   (1.7, 0.5): v1 = 0.3, d = 0.09 -> 1 / 0.09
//   (1, 0.95): v2 = 0.05, d = 0.0025 -> floored at 0.01 -> 100
TEST(LShapeCriteria, AutowareClosenessOfAnLWorkedByHand) {
  Points p = bottom_left_l();
  p.add(1.7, 0.5);
  p.add(1.0, 0.95);
  const double expected = 500.0 + 1.0 / 0.09 + 100.0;
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::autoware_closeness, 0.0), expected, expected * 1e-5);
  // With points counted up to 0.6 m (0.36 m^2) the inner point (1, 0.5) scores 1 / 0.25 = 4 too.
  CriterionConfig config;
  config.autoware_max_dist_m = 0.6;
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::autoware_closeness, 0.0, config), expected + 4.0,
              expected * 1e-5);
  // A floor of 0.04 m^2: the six points at d <= 0.04 score 25 each, (1.7, 0.5) 1 / 0.09.
  config = {};
  config.autoware_min_sq_m2 = 0.04;
  EXPECT_NEAR(criterion_at(p, LShapeCriterion::autoware_closeness, 0.0, config), 6 * 25.0 + 1.0 / 0.09, 1e-3);
}

TEST(LShapeCriteria, EmptyPointSetScoresZeroAndCountsTheEvaluation) {
  const std::vector<double> none;
  for (const LShapeCriterion which : {LShapeCriterion::area, LShapeCriterion::closeness,
                                      LShapeCriterion::variance, LShapeCriterion::autoware_closeness}) {
    CriterionConfig config;
    config.criterion = which;
    CriterionEvaluator evaluate(none, none, config);
    EXPECT_EQ(evaluate(0.4), 0.0);
    EXPECT_EQ(evaluate.evaluations(), 1U);
  }
}

// Points on two faces (the near sides) of a 4.5 x 1.8 rectangle at angle phi, 5 cm apart, centred on the
// origin.
Points two_faces(double phi) {
  Points p;
  const double c = std::cos(phi), s = std::sin(phi);
  auto put = [&](double u, double v) { p.add(c * u - s * v, s * u + c * v); };
  for (double u = -2.25; u <= 2.25 + 1e-9; u += 0.05)
    put(u, -0.9);
  for (double v = -0.9 + 0.05; v <= 0.9 + 1e-9; v += 0.05)
    put(-2.25, v);
  return p;
}

// The expected theta: phi modulo 90 deg, in [0, 90 deg).
double quarter(double phi) {
  const double q = std::fmod(phi, kPi / 2.0);
  return q < 0.0 ? q + kPi / 2.0 : q;
}

TEST(OrientationSearch, FindsTheDirectionOfTheFacesModuloAQuarterTurn) {
  for (const double phi_deg : {0.0, 17.3, 44.0, 61.7, 107.3, -33.1, 179.9}) {
    const Points p = two_faces(deg_to_rad(phi_deg));
    for (const LShapeCriterion which :
         {LShapeCriterion::area, LShapeCriterion::closeness, LShapeCriterion::autoware_closeness}) {
      CriterionConfig cc;
      cc.criterion = which;
      CriterionEvaluator evaluate(p.x, p.y, cc);
      const OrientationResult r = search_orientation(evaluate, OrientationSearchConfig{});
      EXPECT_GE(r.theta, 0.0);
      EXPECT_LT(r.theta, kPi / 2.0);
      // Within 0.1 deg of phi mod 90 (or across the 0 / 90 deg seam). Autoware's criterion floors the
      // distances at 0.1 m, so it is flat over the angles that keep every point within 0.1 m of an edge:
      // the long face turned by up to atan(0.1 / 4.5) = 1.27 deg; the search returns a point of that
      // plateau (its middle, which for an L's two unequal faces need not be phi).
      const double tolerance_deg =
          which == LShapeCriterion::autoware_closeness ? rad_to_deg(std::atan(0.1 / 4.5)) : 0.1;
      const double off = std::abs(std::remainder(r.theta - quarter(deg_to_rad(phi_deg)), kPi / 2.0));
      EXPECT_LT(rad_to_deg(off), tolerance_deg) << phi_deg << " deg, criterion " << static_cast<int>(which);
      // The value reported is the criterion at theta.
      EXPECT_NEAR(r.value, evaluate(r.theta), 1e-9 * std::abs(r.value));
    }
  }
}

TEST(OrientationSearch, ExhaustiveEvaluatesEveryStepOfTheQuarterTurn) {
  const Points p = two_faces(deg_to_rad(30.0));
  CriterionEvaluator evaluate(p.x, p.y, CriterionConfig{});
  OrientationSearchConfig config;
  config.method = OrientationSearchMethod::exhaustive;
  config.exhaustive_step_deg = 1.0;
  const OrientationResult r = search_orientation(evaluate, config);
  // 0, 1, ..., 89 deg: 90 evaluations; the faces lie exactly on the 30 deg step.
  EXPECT_EQ(r.evaluations, 90U);
  EXPECT_NEAR(rad_to_deg(r.theta), 30.0, 1e-6);
  // 7 deg does not divide 90: 0, 7, ..., 84: 13 evaluations; the nearest step to 30 is 28.
  config.exhaustive_step_deg = 7.0;
  const OrientationResult coarse = search_orientation(evaluate, config);
  EXPECT_EQ(coarse.evaluations, 13U);
  EXPECT_NEAR(rad_to_deg(coarse.theta), 28.0, 1e-6);
}

TEST(OrientationSearch, NonPositiveStepSearchesNothing) {
  const Points p = two_faces(0.2);
  CriterionEvaluator evaluate(p.x, p.y, CriterionConfig{});
  for (const double step : {0.0, -1.0, std::nan("")}) {
    OrientationSearchConfig config;
    config.method = OrientationSearchMethod::exhaustive;
    config.exhaustive_step_deg = step;
    const OrientationResult r = search_orientation(evaluate, config);
    EXPECT_EQ(r.evaluations, 0U) << step;
  }
  EXPECT_EQ(evaluate.evaluations(), 0U);
}

// A criterion constant in theta (one point: every edge passes through it) has a plateau over the whole
// circle: the search still answers within [0, 90 deg) with a finite value.
TEST(OrientationSearch, ConstantCriterionGivesAnAngleInRange) {
  Points p;
  p.add(1.0, 2.0);
  for (const auto method : {OrientationSearchMethod::exhaustive, OrientationSearchMethod::coarse_to_fine}) {
    CriterionEvaluator evaluate(p.x, p.y, CriterionConfig{});
    OrientationSearchConfig config;
    config.method = method;
    const OrientationResult r = search_orientation(evaluate, config);
    EXPECT_GE(r.theta, 0.0);
    EXPECT_LT(r.theta, kPi / 2.0);
    EXPECT_NEAR(r.value, 100.0, 1e-3);  // 1 / d0 for the one point
  }
}

}  // namespace criteria_direct_test
}  // namespace rsu::perception
