// SPDX-License-Identifier: Apache-2.0
// A floor under a pose covariance (x, y, yaw): no estimate is credited with more precision than its
// source can have, whatever it states. Used where an outside figure enters the vehicle's filters (an RSU's
// fix, vehicle/vehicle_core.cpp) and where a match's own curvature is turned into a covariance
// (eval/corridor/ndt_localizer.cpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "common/symmetric_eigen.h"

namespace rsu::fusion {

// Raises the position block's eigenvalues to at least sigma_xy^2 (keeping its axes) and the yaw variance
// to at least sigma_yaw^2 (scaling its row and column, so that its correlation with the position stays);
// true when it had to.
inline bool raise_to_floor(Eigen::Matrix3d& c, double sigma_xy, double sigma_yaw) {
  bool raised = false;
  const SymmetricEigen2 eigen(c.topLeftCorner<2, 2>());
  if (eigen.info() == Eigen::Success && eigen.eigenvalues().minCoeff() < sigma_xy * sigma_xy) {
    const Eigen::Vector2d floored = eigen.eigenvalues().cwiseMax(sigma_xy * sigma_xy);
    c.topLeftCorner<2, 2>() = eigen.eigenvectors() * floored.asDiagonal() * eigen.eigenvectors().transpose();
    raised = true;
  }
  if (c(2, 2) < sigma_yaw * sigma_yaw) {
    const double scale = sigma_yaw / std::sqrt(std::max(c(2, 2), 1e-300));
    c.row(2) *= scale;
    c.col(2) *= scale;
    raised = true;
  }
  return raised;
}

// Weakens a pose covariance (x, y, yaw) along one horizontal direction only (`axis_rad`, modulo pi): its
// variance there times `variance_scale` (>= 1), and at least sigma_along^2; across it and in yaw it stays
// as it was. For a match that slides along a street but holds across it (vehicle/vehicle_core.cpp).
inline void weaken_along_axis(Eigen::Matrix3d& c, double axis_rad, double variance_scale,
                              double sigma_along) {
  const Eigen::Vector2d u(std::cos(axis_rad), std::sin(axis_rad));
  const double along = u.dot(c.topLeftCorner<2, 2>() * u);
  const double wanted = std::max(std::max(variance_scale, 1.0) * along, sigma_along * sigma_along);
  c.topLeftCorner<2, 2>() += (wanted - along) * u * u.transpose();
}

}  // namespace rsu::fusion
