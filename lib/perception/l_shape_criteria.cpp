// SPDX-License-Identifier: Apache-2.0
#include "perception/l_shape_criteria.h"

#include "perception/convex_hull.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rsu::perception {
namespace {

// Zhang's D for one direction picks the edge whose distance vector has the smaller 2-norm:
// ||C - c_min||^2 <= ||c_max - C||^2. Expanding both sums of squares, this is mean(C) <= (c_min + c_max) / 2:
// the edge on the side of the points' mean, one comparison instead of a pass over the points.
bool nearer_min_edge(float sum, Eigen::Index n, float c_min, float c_max) {
  return 2.0F * sum <= static_cast<float>(n) * (c_min + c_max);
}

// One direction's distance to its chosen edge as a linear function of the point, d = a x + b y + o, for
// the projection c = px x + py y: c - c_min, or c_max - c (the same float operations as computing c first).
struct EdgeDistance {
  float a, b, o;
};
EdgeDistance edge_distance(float px, float py, float sum, Eigen::Index n, float c_min, float c_max) {
  return nearer_min_edge(sum, n, c_min, c_max) ? EdgeDistance{px, py, -c_min} : EdgeDistance{-px, -py, c_max};
}

// Distances of each point to the chosen edge of one direction.
Eigen::ArrayXf edge_distances(const Eigen::ArrayXf& c, float sum, float c_min, float c_max) {
  return nearer_min_edge(sum, c.size(), c_min, c_max) ? Eigen::ArrayXf(c - c_min) : Eigen::ArrayXf(c_max - c);
}

double population_variance(double sum, double sum_sq, double n) {
  if (n <= 0.0) {
    return 0.0;
  }
  const double mean = sum / n;
  return std::max(0.0, sum_sq / n - mean * mean);
}

}  // namespace

CriterionEvaluator::CriterionEvaluator(std::span<const double> x, std::span<const double> y,
                                       const CriterionConfig& config)
    : config_(config) {
  const auto n = static_cast<Eigen::Index>(std::min(x.size(), y.size()));
  x_.resize(n);
  y_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x_[i] = static_cast<float>(x[static_cast<std::size_t>(i)]);
    y_[i] = static_cast<float>(y[static_cast<std::size_t>(i)]);
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    x_sum_ += static_cast<double>(x_[i]);
    y_sum_ += static_cast<double>(y_[i]);
  }
  const std::vector<std::size_t> hull = convex_hull_vertices({x_.data(), static_cast<std::size_t>(n)},
                                                             {y_.data(), static_cast<std::size_t>(n)});
  hull_x_.resize(static_cast<Eigen::Index>(hull.size()));
  hull_y_.resize(static_cast<Eigen::Index>(hull.size()));
  for (std::size_t k = 0; k < hull.size(); ++k) {
    hull_x_[static_cast<Eigen::Index>(k)] = x_[static_cast<Eigen::Index>(hull[k])];
    hull_y_[static_cast<Eigen::Index>(k)] = y_[static_cast<Eigen::Index>(hull[k])];
  }
}

void CriterionEvaluator::project(float c, float s) {
  c1_ = x_ * c + y_ * s;
  c2_ = y_ * c - x_ * s;
}

double CriterionEvaluator::operator()(double theta) {
  ++evaluations_;
  if (x_.size() == 0) {
    return 0.0;
  }
  const auto c = static_cast<float>(std::cos(theta));
  const auto s = static_cast<float>(std::sin(theta));
  cos_ = c;
  sin_ = s;
  c1_min_ = (hull_x_ * c + hull_y_ * s).minCoeff();
  c1_max_ = (hull_x_ * c + hull_y_ * s).maxCoeff();
  c2_min_ = (hull_y_ * c - hull_x_ * s).minCoeff();
  c2_max_ = (hull_y_ * c - hull_x_ * s).maxCoeff();
  c1_sum_ = static_cast<float>(static_cast<double>(c) * x_sum_ + static_cast<double>(s) * y_sum_);
  c2_sum_ = static_cast<float>(static_cast<double>(c) * y_sum_ - static_cast<double>(s) * x_sum_);
  switch (config_.criterion) {
    case LShapeCriterion::area:
      return area();
    case LShapeCriterion::closeness:
      return closeness_zhang();
    case LShapeCriterion::variance:
      return variance();
    case LShapeCriterion::autoware_closeness:
      return closeness_autoware();
  }
  return 0.0;
}

double CriterionEvaluator::area() const {
  return -static_cast<double>(c1_max_ - c1_min_) * static_cast<double>(c2_max_ - c2_min_);
}

double CriterionEvaluator::closeness_zhang() const {
  // c1 = x cos + y sin, c2 = y cos - x sin = x (-sin) + y cos.
  const EdgeDistance d1 = edge_distance(cos_, sin_, c1_sum_, x_.size(), c1_min_, c1_max_);
  const EdgeDistance d2 = edge_distance(-sin_, cos_, c2_sum_, x_.size(), c2_min_, c2_max_);
  const auto d0 = static_cast<float>(config_.closeness_d0_m);
  return static_cast<double>(
      (x_ * d1.a + y_ * d1.b + d1.o).min(x_ * d2.a + y_ * d2.b + d2.o).max(d0).inverse().sum());
}

double CriterionEvaluator::variance() {
  project(cos_, sin_);
  const Eigen::ArrayXf d1 = edge_distances(c1_, c1_sum_, c1_min_, c1_max_);
  const Eigen::ArrayXf d2 = edge_distances(c2_, c2_sum_, c2_min_, c2_max_);
  // E1 = {D1(i) : D1(i) < D2(i)}, E2 = {D2(i) : D2(i) < D1(i)}; ties belong to neither.
  const auto in1 = (d1 < d2).cast<float>();
  const auto in2 = (d2 < d1).cast<float>();
  const double v1 =
      population_variance(static_cast<double>((in1 * d1).sum()), static_cast<double>((in1 * d1 * d1).sum()),
                          static_cast<double>(in1.sum()));
  const double v2 =
      population_variance(static_cast<double>((in2 * d2).sum()), static_cast<double>((in2 * d2 * d2).sum()),
                          static_cast<double>(in2.sum()));
  return -v1 - v2;
}

double CriterionEvaluator::closeness_autoware() {
  project(cos_, sin_);
  // Element-wise nearer edge, squared.
  const Eigen::ArrayXf v1 = (c1_max_ - c1_).min(c1_ - c1_min_);
  const Eigen::ArrayXf v2 = (c2_max_ - c2_).min(c2_ - c2_min_);
  const Eigen::ArrayXf d = (v1 * v1).min(v2 * v2);
  const auto max_sq = static_cast<float>(config_.autoware_max_dist_m * config_.autoware_max_dist_m);
  const auto min_sq = static_cast<float>(config_.autoware_min_sq_m2);
  return static_cast<double>((d <= max_sq).select(d.max(min_sq).inverse(), 0.0F).sum());
}

}  // namespace rsu::perception
