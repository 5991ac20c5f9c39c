// SPDX-License-Identifier: Apache-2.0
// The fine stage of the mount calibration: Gauss-Newton on point-to-plane distances between the
// background scan and the map's local planes, and the information that the fit carries about the pose.
//
// The pose is perturbed about the sensor, in the map frame: t' = t + dt, R' = exp([w]x) R, so that dt is a
// displacement of the sensor and w a small rotation about it. A background point p (sensor frame) lands
// at a = R p + t; its residual against the plane (point q, unit normal n) is r = n . (a - q), with
// dr/d(dt, w) = (n, (a - t) x n).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/pose.h"

namespace rsu::calibration {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// A background point matched to a plane of the map.
struct PlaneMatch {
  Eigen::Vector3d sensor_point;  // sensor frame
  Eigen::Vector3d plane_point;   // map frame
  Eigen::Vector3d normal;        // map frame, unit
  double sigma_m = 0.02;         // the residual's expected standard deviation (the sensor's noise along n)
};

struct PlaneFit {
  Vector6d step = Vector6d::Zero();         // (dt, w) that minimises the weighted residuals
  Matrix6d information = Matrix6d::Zero();  // J^T W J / sigma^2 in (dt, w); its inverse is the covariance
  double rms_m = 0.0;                       // residual rms (m) before the step
  double scale = 0.0;  // residuals against their expected sigmas: sqrt(sum w (r / sigma)^2 / (n - 6))
  std::size_t matches = 0;
  std::size_t vertical_matches = 0;  // of planes with a mostly horizontal normal (walls, poles)
};

// One Gauss-Newton step at `pose`, each residual weighted by its expected variance and by Huber's weight
// beyond huber_sigmas of it: the points beyond count less, since a background holds things the map has
// not (parked cars, passers-by). The information is scaled by the residuals found (scale^2), so a noisier
// fit than expected states a larger covariance.
PlaneFit fit_planes(const std::vector<PlaneMatch>& matches, const Pose3& pose, double huber_sigmas);

// pose moved by (dt, w) as above.
Pose3 apply_step(const Pose3& pose, const Vector6d& step);

// d(x, y, z, roll, pitch, yaw) / d(dt, w) at `pose`: carries a covariance in (dt, w) to the mount's
// parameters (roll, pitch, yaw as in Pose3).
Matrix6d pose_parameter_jacobian(const Pose3& pose);

// roll, pitch, yaw of a rotation R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d roll_pitch_yaw(const Eigen::Matrix3d& rotation);

}  // namespace rsu::calibration
