// SPDX-License-Identifier: Apache-2.0
#include "calibration/point_to_plane.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/angles.h"
#include "common/symmetric_eigen.h"

namespace rsu::calibration {

PlaneFit fit_planes(const std::vector<PlaneMatch>& matches, const Pose3& pose, double huber_sigmas) {
  PlaneFit fit;
  fit.matches = matches.size();
  const Eigen::Isometry3d t = pose.to_isometry();
  Matrix6d jtj = Matrix6d::Zero();
  Vector6d jtr = Vector6d::Zero();
  double normalized_squares = 0.0;
  double squares = 0.0;
  for (const PlaneMatch& m : matches) {
    const Eigen::Vector3d a = t * m.sensor_point;
    const double r = m.normal.dot(a - m.plane_point);
    Vector6d j;
    j.head<3>() = m.normal;
    j.tail<3>() = (a - t.translation()).cross(m.normal);
    const double z = std::abs(r) / m.sigma_m;
    const double w = (z <= huber_sigmas ? 1.0 : huber_sigmas / z) / (m.sigma_m * m.sigma_m);
    jtj += w * j * j.transpose();
    jtr += w * j * r;
    normalized_squares += w * r * r;
    squares += r * r;
    if (std::abs(m.normal.z()) < 0.5)
      ++fit.vertical_matches;
  }
  if (matches.size() <= 6)
    return fit;
  fit.rms_m = std::sqrt(squares / static_cast<double>(matches.size()));
  fit.scale = std::sqrt(normalized_squares / static_cast<double>(matches.size() - 6));
  // A pseudo-inverse, so that a direction nothing constrains (a featureless street) takes no step
  // instead of a wild one; the information matrix still shows it.
  const SymmetricEigen6 eigen(jtj);
  const double largest = eigen.eigenvalues().maxCoeff();
  Vector6d step = Vector6d::Zero();
  for (int i = 0; i < 6; ++i) {
    const double lambda = eigen.eigenvalues()[i];
    if (lambda > 1e-9 * largest) {
      const Vector6d v = eigen.eigenvectors().col(i);
      step -= v * (v.dot(jtr) / lambda);
    }
  }
  fit.step = step;
  fit.information = jtj / (fit.scale * fit.scale);
  return fit;
}

Pose3 apply_step(const Pose3& pose, const Vector6d& step) {
  const Eigen::Vector3d w = step.tail<3>();
  const double angle = w.norm();
  const Eigen::Matrix3d delta =
      angle > 0.0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  const Eigen::Vector3d rpy = roll_pitch_yaw(delta * pose.to_isometry().linear());
  return Pose3{pose.x + step[0], pose.y + step[1], pose.z + step[2], rpy[0], rpy[1], rpy[2]};
}

Matrix6d pose_parameter_jacobian(const Pose3& pose) {
  Matrix6d jacobian = Matrix6d::Identity();
  constexpr double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Vector6d plus = Vector6d::Zero();
    plus[3 + k] = h;
    Vector6d minus = Vector6d::Zero();
    minus[3 + k] = -h;
    const Pose3 a = apply_step(pose, plus);
    const Pose3 b = apply_step(pose, minus);
    const Eigen::Vector3d d(wrap_angle(a.roll - b.roll), wrap_angle(a.pitch - b.pitch),
                            wrap_angle(a.yaw - b.yaw));
    jacobian.block<3, 1>(3, 3 + k) = d / (2 * h);
  }
  return jacobian;
}

Eigen::Vector3d roll_pitch_yaw(const Eigen::Matrix3d& r) {
  return Eigen::Vector3d(std::atan2(r(2, 1), r(2, 2)), std::asin(std::clamp(-r(2, 0), -1.0, 1.0)),
                         std::atan2(r(1, 0), r(0, 0)));
}

}  // namespace rsu::calibration
