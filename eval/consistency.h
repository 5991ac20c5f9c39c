// SPDX-License-Identifier: Apache-2.0
// Is a stated uncertainty honest? The experiments score every estimate's position error against the
// covariance it came with: the normalized estimation error squared (NEES, e^T P^-1 e) of the 2D position,
// and the share of estimates beyond the 3-sigma bound, i.e. with a 2-dof NEES beyond its 99.73 % quantile
// (the same tail as 3 sigma in one dimension). An honest Gaussian estimate is beyond it 0.27 % of the
// time; a much larger share means an overconfident source, which a fusing filter then trusts too much.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace rsu::eval {

// 2-dof chi-square quantile of 99.73 %: -2 ln(1 - 0.9973).
inline constexpr double kChi2TwoDof3Sigma = 11.83;

inline double position_nees(const Eigen::Vector2d& error, const Eigen::Matrix2d& covariance) {
  return error.dot(covariance.ldlt().solve(error));
}

}  // namespace rsu::eval
