// SPDX-License-Identifier: Apache-2.0
#include "calibration/mount_verdict.h"

#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Core>

#include "common/angles.h"
#include "common/symmetric_eigen.h"

namespace rsu::calibration {

namespace {
constexpr double kLeverArmM = 10.0;

// The largest-variance direction of a 3x3 block of the (dt, w) covariance.
void weakest(const Eigen::Matrix3d& block, Eigen::Vector3d& direction, double& sigma) {
  const SymmetricEigen3 eigen(block);
  direction = eigen.eigenvectors().col(2);
  const double variance = eigen.eigenvalues()[2];
  sigma = std::isfinite(variance) && variance >= 0.0 ? std::sqrt(variance)
                                                     : std::numeric_limits<double>::infinity();
}

std::string vector_text(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out.precision(2);
  out << std::fixed << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return out.str();
}
}  // namespace

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kGood:
      return "good";
    case Verdict::kAmbiguous:
      return "ambiguous";
    case Verdict::kFailed:
      return "failed";
  }
  return "failed";
}

MountUncertainty mount_uncertainty(const PlaneFit& fit, const Pose3& pose, const ModelFloor& floor) {
  MountUncertainty u;
  Matrix6d scaled = fit.information;
  scaled.bottomRows<3>() /= kLeverArmM;
  scaled.rightCols<3>() /= kLeverArmM;
  const SymmetricEigen6 eigen(scaled);
  const double largest = eigen.eigenvalues().maxCoeff();
  u.information_ratio = largest > 0.0 ? std::max(0.0, eigen.eigenvalues().minCoeff()) / largest : 0.0;

  // Inverse over the directions the fit holds; a free direction gets infinite variance.
  const SymmetricEigen6 info(fit.information);
  const double top = info.eigenvalues().maxCoeff();
  Matrix6d covariance = Matrix6d::Zero();
  bool free_direction = !(top > 0.0);
  for (int i = 0; i < 6 && !free_direction; ++i) {
    const double lambda = info.eigenvalues()[i];
    if (!(lambda > 1e-12 * top)) {
      free_direction = true;
      break;
    }
    covariance += info.eigenvectors().col(i) * info.eigenvectors().col(i).transpose() / lambda;
  }
  if (free_direction) {
    u.covariance = Matrix6d::Identity() * std::numeric_limits<double>::infinity();
    u.weakest_position_sigma_m = u.weakest_rotation_sigma_rad = std::numeric_limits<double>::infinity();
    return u;
  }
  weakest(covariance.topLeftCorner<3, 3>(), u.weakest_position_direction, u.weakest_position_sigma_m);
  weakest(covariance.bottomRightCorner<3, 3>(), u.weakest_rotation_axis, u.weakest_rotation_sigma_rad);
  const Matrix6d j = pose_parameter_jacobian(pose);
  u.covariance = j * covariance * j.transpose();
  for (int i = 0; i < 3; ++i) {
    u.covariance(i, i) += floor.position_sigma_m * floor.position_sigma_m;
    u.covariance(3 + i, 3 + i) += floor.angle_sigma_rad * floor.angle_sigma_rad;
  }
  return u;
}

VerdictResult judge(const PlaneFit& fit, const MountUncertainty& u, const VerdictLimits& limits) {
  std::ostringstream reason;
  if (fit.matches < limits.min_matches) {
    reason << "too few structures: " << fit.matches
           << " background points matched the map's planes (at least " << limits.min_matches << " needed)";
    return {Verdict::kFailed, reason.str()};
  }
  if (fit.vertical_matches < limits.min_vertical_matches) {
    reason << "too few structures: " << fit.vertical_matches << " points on walls or poles (at least "
           << limits.min_vertical_matches << "); the ground alone fixes no position along it nor yaw";
    return {Verdict::kFailed, reason.str()};
  }
  if (fit.rms_m > limits.max_rms_m) {
    reason << "the background does not fit the map: residual rms " << fit.rms_m << " m (at most "
           << limits.max_rms_m << " m)";
    return {Verdict::kFailed, reason.str()};
  }
  if (!(u.weakest_position_sigma_m <= limits.max_sigma_position_m) ||
      !(u.weakest_rotation_sigma_rad <= limits.max_sigma_angle_rad)) {
    reason << "degenerate direction: the map holds the sensor weakly along "
           << vector_text(u.weakest_position_direction) << " (sigma " << u.weakest_position_sigma_m
           << " m) and about " << vector_text(u.weakest_rotation_axis) << " (sigma "
           << rad_to_deg(u.weakest_rotation_sigma_rad) << " deg); information ratio " << u.information_ratio
           << " (a street with nothing along it?)";
    return {Verdict::kAmbiguous, reason.str()};
  }
  reason << "weakest direction " << vector_text(u.weakest_position_direction) << " sigma "
         << u.weakest_position_sigma_m << " m; weakest rotation sigma "
         << rad_to_deg(u.weakest_rotation_sigma_rad) << " deg";
  return {Verdict::kGood, reason.str()};
}

}  // namespace rsu::calibration
