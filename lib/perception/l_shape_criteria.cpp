#include "perception/l_shape_criteria.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rsu::perception {
namespace {

// Zhang's D for one direction picks the edge whose distance vector has the smaller 2-norm:
// ||C - c_min||^2 <= ||c_max - C||^2. Expanding both sums of squares, this is mean(C) <= (c_min + c_max) / 2:
// the edge on the side of the points' mean, one comparison instead of a pass over the points.
bool nearer_min_edge(double sum, std::size_t n, double c_min, double c_max) {
  return 2.0 * sum <= static_cast<double>(n) * (c_min + c_max);
}

double population_variance(double sum, double sum_sq, std::size_t n) {
  if (n == 0) {
    return 0.0;
  }
  const double mean = sum / static_cast<double>(n);
  return std::max(0.0, sum_sq / static_cast<double>(n) - mean * mean);
}

}  // namespace

CriterionEvaluator::CriterionEvaluator(std::span<const double> x, std::span<const double> y,
                                       const CriterionConfig& config)
    : x_(x), y_(y.first(std::min(x.size(), y.size()))), config_(config), c1_(y_.size()), c2_(y_.size()) {
  x_ = x_.first(y_.size());
}

double CriterionEvaluator::operator()(double theta) {
  ++evaluations_;
  if (x_.empty()) {
    return 0.0;
  }
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  c1_min_ = c2_min_ = std::numeric_limits<double>::infinity();
  c1_max_ = c2_max_ = -std::numeric_limits<double>::infinity();
  c1_sum_ = c2_sum_ = 0.0;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const double a = x_[i] * c + y_[i] * s;
    const double b = -x_[i] * s + y_[i] * c;
    c1_[i] = a;
    c2_[i] = b;
    c1_sum_ += a;
    c2_sum_ += b;
    c1_min_ = std::min(c1_min_, a);
    c1_max_ = std::max(c1_max_, a);
    c2_min_ = std::min(c2_min_, b);
    c2_max_ = std::max(c2_max_, b);
  }
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

double CriterionEvaluator::area() const { return -(c1_max_ - c1_min_) * (c2_max_ - c2_min_); }

double CriterionEvaluator::closeness_zhang() const {
  const bool min1 = nearer_min_edge(c1_sum_, c1_.size(), c1_min_, c1_max_);
  const bool min2 = nearer_min_edge(c2_sum_, c2_.size(), c2_min_, c2_max_);
  const double d0 = config_.closeness_d0_m;
  double beta = 0.0;
  for (std::size_t i = 0; i < c1_.size(); ++i) {
    const double d1 = min1 ? c1_[i] - c1_min_ : c1_max_ - c1_[i];
    const double d2 = min2 ? c2_[i] - c2_min_ : c2_max_ - c2_[i];
    beta += 1.0 / std::max(std::min(d1, d2), d0);
  }
  return beta;
}

double CriterionEvaluator::variance() const {
  const bool min1 = nearer_min_edge(c1_sum_, c1_.size(), c1_min_, c1_max_);
  const bool min2 = nearer_min_edge(c2_sum_, c2_.size(), c2_min_, c2_max_);
  double s1 = 0.0, q1 = 0.0, s2 = 0.0, q2 = 0.0;
  std::size_t n1 = 0, n2 = 0;
  for (std::size_t i = 0; i < c1_.size(); ++i) {
    const double d1 = min1 ? c1_[i] - c1_min_ : c1_max_ - c1_[i];
    const double d2 = min2 ? c2_[i] - c2_min_ : c2_max_ - c2_[i];
    if (d1 < d2) {
      s1 += d1;
      q1 += d1 * d1;
      ++n1;
    } else if (d2 < d1) {
      s2 += d2;
      q2 += d2 * d2;
      ++n2;
    }
  }
  return -population_variance(s1, q1, n1) - population_variance(s2, q2, n2);
}

double CriterionEvaluator::closeness_autoware() const {
  const double max_sq = config_.autoware_max_dist_m * config_.autoware_max_dist_m;
  double beta = 0.0;
  for (std::size_t i = 0; i < c1_.size(); ++i) {
    const double v1 = std::min(c1_max_ - c1_[i], c1_[i] - c1_min_);
    const double v2 = std::min(c2_max_ - c2_[i], c2_[i] - c2_min_);
    const double d = std::min(v1 * v1, v2 * v2);
    if (d > max_sq) {
      continue;
    }
    beta += 1.0 / std::max(d, config_.autoware_min_sq_m2);
  }
  return beta;
}

}  // namespace rsu::perception
