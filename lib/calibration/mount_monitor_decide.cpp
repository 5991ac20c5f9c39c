// SPDX-License-Identifier: Apache-2.0
// MountMonitor::decide (mount_monitor.h): what the monitor decides on, along the directions one rotation
// pins down only weakly, from the window's rotations.
#include <algorithm>
#include <tuple>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "calibration/mount_monitor.h"

#include "common/symmetric_eigen.h"

namespace rsu::calibration {
namespace {

// A small motion's parameters as a vector (x, y, z, roll, pitch, yaw), to first order the perturbation
// (dt, w) the covariance is of (point_to_plane.h): means of a few rotations' estimates are taken on it.
Vector6d parameters(const Pose3& p) {
  Vector6d v;
  v << p.x, p.y, p.z, p.roll, p.pitch, p.yaw;
  return v;
}

Pose3 from_parameters(const Vector6d& v) {
  return Pose3{v[0], v[1], v[2], v[3], v[4], v[5]};
}

}  // namespace

// The directions of the newest rotation's estimate, in metres at the coverage radius: those it pins down
// to the tolerance over significance_sigmas are its own to decide (a bump shows at once); those it holds
// only weakly (up to max_free_sigma_m: beyond, held_step does not estimate them) take the
// information-weighted mean of the window's estimates there (each rotation's noise its own: they are
// registered from the reference, not from each other). The mean's covariance is scaled by the spread the
// window shows about it when that exceeds the stated one (chi-square per degree of freedom, as the fit
// scales its residuals): along such a direction one rotation's stated sigma is not to be trusted (the
// load street's still 128-ring at 20 Hz: 2.0 cm stated, 5 cm rms, tails to 15 cm; the VLP-32C: 2.1 cm
// stated, 2.4 cm rms, tails to 11 cm), and three rotations in a row beyond the tolerance there had
// stopped a still sensor's fixes for good. Until the mean rests on suspect_rotations rotations and its
// sigma verifies the tolerance (start-up; a spread too wide), those directions are held at the reference
// as a free one is, their covariance saying so: a motion along them is seen once the mean shows it.
MountDrift MountMonitor::decide(const MountDrift& newest) const {
  const Vector6d scale = reference_->at_radius_scale();
  const Matrix6d covariance = scale.asDiagonal() * newest.covariance * scale.asDiagonal();
  const SymmetricEigen6 eigen(covariance);
  const double tolerance = config().max_position_error_m;
  const double verified_sigma = tolerance / config().significance_sigmas;
  std::vector<int> weak;
  for (int k = 0; k < 6; ++k) {
    const double variance = eigen.eigenvalues()[k];
    if (variance > verified_sigma * verified_sigma &&
        variance <= config().max_free_sigma_m * config().max_free_sigma_m)
      weak.push_back(k);
  }
  if (weak.empty())
    return newest;
  const auto m = static_cast<Eigen::Index>(weak.size());
  Eigen::MatrixXd directions(6, m);
  for (Eigen::Index j = 0; j < m; ++j)
    directions.col(j) = eigen.eigenvectors().col(weak[static_cast<std::size_t>(j)]);
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(m, m);
  // Each rotation's estimate along these directions and the information of its marginal covariance there.
  std::vector<Eigen::VectorXd> estimates;
  std::vector<Eigen::MatrixXd> informations;
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd weighted = Eigen::VectorXd::Zero(m);
  for (const Evidence& e : recent_) {
    const Eigen::MatrixXd c =
        directions.transpose() * scale.asDiagonal() * e.covariance * scale.asDiagonal() * directions;
    informations.push_back(c.ldlt().solve(identity));
    estimates.push_back(directions.transpose() * scale.asDiagonal() * parameters(e.motion));
    information += informations.back();
    weighted += informations.back() * estimates.back();
  }
  Eigen::MatrixXd mean_covariance = information.ldlt().solve(identity);
  Eigen::VectorXd mean = mean_covariance * weighted;
  double chi_square = 0.0;
  for (std::size_t i = 0; i < estimates.size(); ++i)
    chi_square += (estimates[i] - mean).dot(informations[i] * (estimates[i] - mean));
  const double degrees = static_cast<double>(m) * static_cast<double>(estimates.size() - 1);
  if (degrees > 0.0)
    mean_covariance *= std::max(1.0, chi_square / degrees);
  MountDrift d = newest;
  // The mean's largest variance: its m x m covariance in a 6 x 6 of zeros (the same largest eigenvalue;
  // the 6 x 6 solver is compiled once, common/symmetric_eigen.h).
  Matrix6d padded = Matrix6d::Zero();
  padded.topLeftCorner(m, m) = mean_covariance;
  const bool verified = static_cast<int>(estimates.size()) >= config().suspect_rotations &&
                        SymmetricEigen6(padded).eigenvalues().maxCoeff() <= verified_sigma * verified_sigma;
  if (verified) {
    d.rotations_averaged = static_cast<int>(estimates.size());
  } else {
    mean.setZero();  // held at the reference
    mean_covariance = directions.transpose() * covariance * directions;
    d.weak_held = true;
  }
  // The newest rotation's estimate and covariance with their weak part replaced.
  const Vector6d newest_scaled = scale.asDiagonal() * parameters(newest.motion);
  const Matrix6d others =
      covariance - directions * (directions.transpose() * covariance * directions) * directions.transpose();
  d.motion =
      from_parameters(scale.cwiseInverse().asDiagonal() *
                      Vector6d(newest_scaled + directions * (mean - directions.transpose() * newest_scaled)));
  d.covariance = scale.cwiseInverse().asDiagonal() *
                 Matrix6d(others + directions * mean_covariance * directions.transpose()) *
                 scale.cwiseInverse().asDiagonal();
  std::tie(d.error_at_radius_m, d.error_sigma_m) = reference_->error_at_radius(d.motion, d.covariance);
  if (verified) {
    const Matrix6d weak_covariance = scale.cwiseInverse().asDiagonal() *
                                     Matrix6d(directions * mean_covariance * directions.transpose()) *
                                     scale.cwiseInverse().asDiagonal();
    d.weak_sigma_m = reference_->error_at_radius(d.motion, weak_covariance).second;
  }
  return d;
}

}  // namespace rsu::calibration
