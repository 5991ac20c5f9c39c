// SPDX-License-Identifier: Apache-2.0
#include "perception/fix_covariance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/symmetric_eigen.h"

namespace rsu::perception {
namespace {

double axis_variance(const AxisEvidence& axis, double noise_var, double spacing, double shape_var) {
  switch (axis.anchor) {
    case AxisAnchor::face:
      return (axis.envelope_sigma_m >= 0.0
                  ? axis.envelope_sigma_m * axis.envelope_sigma_m
                  : noise_var / static_cast<double>(std::max<std::size_t>(axis.face_points, 1))) +
             shape_var;
    case AxisAnchor::interval:
      return axis.interval_m * axis.interval_m / 12.0 + noise_var + shape_var;
    case AxisAnchor::midpoint:
      return spacing * spacing / 24.0 + axis.interval_m * axis.interval_m / 12.0 + noise_var / 2.0 +
             shape_var;
    case AxisAnchor::one_end:
      return spacing * spacing / 3.0 + noise_var + shape_var;
  }
  return noise_var + shape_var;
}

// The smallest-volume ellipse holding both ellipses x' A^-1 x <= 1 and x' B^-1 x <= 1 among those sharing
// their conjugate axes: in the basis where A is the unit matrix, B's eigenvalues each raised to at least 1.
// Both are made positive definite by `floor` on the diagonal (a rank-one A or B is common: one lever).
Eigen::Matrix2d common_cover(const Eigen::Matrix2d& a, const Eigen::Matrix2d& b, double floor) {
  const Eigen::Matrix2d a_pd = a + floor * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d b_pd = b + floor * Eigen::Matrix2d::Identity();
  const SymmetricEigen2 ea(a_pd);
  const Eigen::Matrix2d root = ea.eigenvectors() * ea.eigenvalues().cwiseSqrt().asDiagonal() *
                               ea.eigenvectors().transpose();  // A^(1/2)
  const Eigen::Matrix2d inv_root = ea.eigenvectors() *
                                   ea.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() *
                                   ea.eigenvectors().transpose();  // A^(-1/2)
  const SymmetricEigen2 eb(inv_root * b_pd * inv_root);
  const Eigen::Vector2d raised = eb.eigenvalues().cwiseMax(1.0);
  return root * eb.eigenvectors() * raised.asDiagonal() * eb.eigenvectors().transpose() * root;
}

}  // namespace

double point_noise_variance(double range_m, const CovarianceModelConfig& config) {
  if (!std::isfinite(range_m))
    return std::numeric_limits<double>::infinity();  // an unknown range bounds nothing
  const double range = std::max(0.0, range_m);
  return config.range_sigma_m * config.range_sigma_m +
         (range * config.angle_sigma_rad) * (range * config.angle_sigma_rad);
}

FaceEvidence face_evidence(const RectangleFit& fit, std::size_t edge, const Eigen::Vector2d& lidar_xy) {
  const Eigen::Vector2d& a = fit.corners[edge % 4];
  const Eigen::Vector2d& b = fit.corners[(edge + 1) % 4];
  const Eigen::Vector2d along = b - a;
  const Eigen::Vector2d sight = 0.5 * (a + b) - lidar_xy;
  const double norms = along.norm() * sight.norm();
  const double incidence_sin =
      norms > 0.0 ? std::abs(along.x() * sight.y() - along.y() * sight.x()) / norms : 1.0;
  return {fit.edges[edge % 4].support_points, edge % 2 == 0 ? fit.length0 : fit.length1, incidence_sin};
}

double face_yaw_information(const FixEvidence& e, const CovarianceModelConfig& config) {
  const double noise_var = point_noise_variance(e.range_m, config);
  double yaw_information = 0.0;
  for (const auto& face : e.seen_faces) {
    if (face.points >= 2 && face.length_m > 0.0) {
      // Point noise averages out over the face's points; the body's departure from a plane does not
      // (fix_covariance.h): it tilts the face's fitted direction by about 2 tilt / length whatever the
      // number of points, more at grazing incidence.
      const double l2 = face.length_m * face.length_m;
      const double var_noise = 12.0 * noise_var / (static_cast<double>(face.points) * l2);
      const double sin_incidence = std::clamp(face.incidence_sin, config.min_incidence_sin, 1.0);
      // The measured departure: the face points' scatter beyond what the point noise explains.
      const double departure_var = std::max(0.0, face.residual_spread_m * face.residual_spread_m - noise_var);
      const double tilt = std::sqrt(config.face_tilt_sigma_m * config.face_tilt_sigma_m + departure_var +
                                    face.departure_m * face.departure_m) /
                          sin_incidence;
      const double var_shape = 4.0 * tilt * tilt / l2;
      yaw_information += 1.0 / (var_noise + var_shape);
    }
  }
  if (yaw_information > 0.0 && e.faces_unsettled_rad > 0.0)
    yaw_information = 1.0 / (1.0 / yaw_information + e.faces_unsettled_rad * e.faces_unsettled_rad);
  return yaw_information;
}

Eigen::Matrix3d fix_covariance(const FixEvidence& e, const CovarianceModelConfig& config) {
  const double max_var = config.max_yaw_sigma_rad * config.max_yaw_sigma_rad;
  // Without a range the points' noise is unknown: the position is unbounded (position_sigma_m infinite,
  // every cap refuses it) and the yaw as uncertain as a fix may state.
  if (!std::isfinite(e.range_m)) {
    Eigen::Matrix3d unbounded = Eigen::Matrix3d::Zero();
    unbounded(0, 0) = unbounded(1, 1) = std::numeric_limits<double>::infinity();
    unbounded(2, 2) = max_var;
    return unbounded;
  }
  const double range = std::max(0.0, e.range_m);
  const double noise_var = point_noise_variance(range, config);
  const double shape_var = config.shape_sigma_m * config.shape_sigma_m;
  const double spacing = range * config.azimuth_resolution_rad;

  const double yaw_information = face_yaw_information(e, config) + std::max(0.0, e.prior_yaw_information);
  double var_yaw = yaw_information > 0.0 ? 1.0 / yaw_information : max_var;
  var_yaw += config.search_resolution_rad * config.search_resolution_rad / 12.0;
  var_yaw = std::min(var_yaw, max_var);

  const Eigen::Vector2d u(std::cos(e.yaw), std::sin(e.yaw));  // length axis
  const Eigen::Vector2d v(-u.y(), u.x());                     // width axis
  const double var_u = axis_variance(e.length_axis, noise_var, spacing, shape_var);
  const double var_v = axis_variance(e.width_axis, noise_var, spacing, shape_var);
  Eigen::Matrix2d pos = var_u * u * u.transpose() + var_v * v * v.transpose();
  // A yaw error turns the box about where its evidence lies; when the centre itself is uncertain along
  // one axis (the interval a partial view leaves), the turn moves it across by the yaw error times that
  // uncertainty too: the product of two independent errors.
  pos += var_yaw * (var_v * u * u.transpose() + var_u * v * v.transpose());

  // d(centre)/d(yaw): from the lever (a small turn about the evidence), and measured by placing the box
  // again at the probes (the lever's where a probe's box did not hold the points). The turn's spread
  // covers both: the probes, far out, may re-anchor the box along one axis while a small yaw error turns
  // it across the other (an SUV 36 m from a VLP-16, its rear and the rear of its side seen: the probe
  // moved it 0.9 m along, the lever says 1.9 m/rad across; 5.4 deg off, it was 0.18 m off across stating
  // 0.05 m there, NEES 14.6, when the larger of the two stood alone).
  const Eigen::Vector2d lever_j(-e.lever.y(), e.lever.x());
  std::array<Eigen::Vector2d, 2> j{lever_j, lever_j};
  for (std::size_t i = 0; i < 2; ++i) {
    if (e.yaw_probe_rad[i] != 0.0 && std::isfinite(e.yaw_probe_rad[i]) && e.yaw_probe_shift[i].allFinite())
      j[i] = e.yaw_probe_shift[i] / e.yaw_probe_rad[i];
  }
  const Eigen::Matrix2d probes = 0.5 * (j[0] * j[0].transpose() + j[1] * j[1].transpose());
  const Eigen::Matrix2d turn = common_cover(probes, lever_j * lever_j.transpose(), 1e-6);
  const Eigen::Vector2d mean_j = lever_j.squaredNorm() > probes.trace() ? lever_j : 0.5 * (j[0] + j[1]);
  pos += var_yaw * turn;
  const Eigen::Vector2d pos_yaw = var_yaw * mean_j;  // a yaw error moves the centre along j

  const double wrong = std::clamp(1.0 - e.assignment_confidence, 0.0, 1.0);
  pos += wrong * e.alternative_offset * e.alternative_offset.transpose();
  var_yaw += wrong * (std::numbers::pi / 2.0) * (std::numbers::pi / 2.0);

  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov.topLeftCorner<2, 2>() = pos;
  cov.block<2, 1>(0, 2) = pos_yaw;
  cov.block<1, 2>(2, 0) = pos_yaw.transpose();
  cov(2, 2) = var_yaw;
  return cov;
}

}  // namespace rsu::perception
