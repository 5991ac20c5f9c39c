// SPDX-License-Identifier: Apache-2.0
// The rectangle-fitting criteria of Zhang et al. 2017, "Efficient L-Shape Fitting for Vehicle Detection
// Using Laser Scanners" (IV 2017), Algorithms 3-5, plus Autoware's variant of the closeness criterion.
// For a candidate angle theta the points are projected on e1 = (cos, sin) and e2 = (-sin, cos); the
// criterion scores how well the rectangle with edges along e1, e2 bounding the points explains them
// (higher is better). All are periodic in theta with period pi/2, so theta is searched in [0, 90 deg).
//
//  - area (Alg. 3): minus the bounding-rectangle area.
//  - closeness (Alg. 4), the default: for each direction, D is whichever of the vectors
//    (c_max - C) and (C - c_min) has the smaller 2-norm, i.e. the points' distances to the one of the two
//    parallel edges the points lie along as a whole; each point contributes 1 / max(min(D1, D2), d0),
//    d0 = 0.01 m (Zhang). A point counts for the edge it is nearer to.
//  - variance (Alg. 5): with the same D1, D2, minus the variances of the distances of the points
//    assigned to each edge (E1 = {D1(i) : D1(i) < D2(i)}, E2 likewise).
//  - autoware_closeness (Autoware shape_estimation, docs/design.md §2): the element-wise nearer edge per
//    point, squared distances floored at 0.01 m^2 (= (0.1 m)^2), and points farther than 0.4 m from
//    both edges ignored.
#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

namespace rsu::perception {

enum class LShapeCriterion { area, closeness, variance, autoware_closeness };

struct CriterionConfig {
  LShapeCriterion criterion = LShapeCriterion::closeness;
  double closeness_d0_m = 0.01;      // Zhang's d0
  double autoware_min_sq_m2 = 0.01;  // Autoware: floor of the squared distance
  double autoware_max_dist_m = 0.4;  // Autoware: points farther than this from both edges ignored
};

// Evaluates the chosen criterion on a fixed point set (x, y given relative to any origin; centring them
// near the centroid keeps the projections well conditioned). Keeps scratch buffers, so one evaluator is
// meant for one point set and one thread. Single precision on Eigen arrays (vectorised): coordinates
// are centred within a few metres, so float resolves them to micrometres, far below d0.
// A near car on a dense sensor is 10-17 thousand points and a search evaluates ~165 angles, so each
// evaluation is one pass over the points: the rectangle's edges (the projections' extremes) come from
// the convex hull's vertices (convex_hull.h), the projections' sums from the coordinates' sums (the sum
// of projections is the projection of the sum), and closeness and area fuse the rest into one
// expression without temporaries. The same criterion as the pass-per-quantity reference, to float
// rounding (l_shape_test checks it on real clusters).
class CriterionEvaluator {
 public:
  CriterionEvaluator(std::span<const double> x, std::span<const double> y, const CriterionConfig& config);

  double operator()(double theta);
  std::size_t evaluations() const { return evaluations_; }

 private:
  double area() const;
  double closeness_zhang() const;
  double variance();
  double closeness_autoware();

  void project(float c, float s);

  CriterionConfig config_;
  Eigen::ArrayXf x_;
  Eigen::ArrayXf y_;
  Eigen::ArrayXf hull_x_;  // the convex hull's vertices: where the projections' extremes lie
  Eigen::ArrayXf hull_y_;
  double x_sum_ = 0.0, y_sum_ = 0.0;
  float cos_ = 1.0F, sin_ = 0.0F;
  Eigen::ArrayXf c1_;
  Eigen::ArrayXf c2_;
  float c1_min_ = 0, c1_max_ = 0, c2_min_ = 0, c2_max_ = 0;
  float c1_sum_ = 0, c2_sum_ = 0;
  std::size_t evaluations_ = 0;
};

}  // namespace rsu::perception
