// SPDX-License-Identifier: Apache-2.0
#include "calibration/mount_reference.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "calibration/coarse_search.h"
#include "common/angles.h"
#include "common/symmetric_eigen.h"
#include "lidar/point_eigen.h"

namespace rsu::calibration {
namespace {

struct Scatter {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int n = 0;
};

// The information the estimate states (its covariance's inverse): residuals smaller than the sensor's
// stated noise (a simulator without noise) must not make it look more certain than the sensor is, so the
// fit's scale is floored at 1. held_step holds directions on it too, so that a direction the covariance
// states free is not estimated (the mis-association street with the LiDAR 6 m up: 2.6 cm stated along
// it, yet stepped along on the fit's own information, single rotations 5-7 cm off, beyond the tolerance
// on 37 of 78 rotations).
Matrix6d stated_information(const PlaneFit& fit) {
  return fit.information * std::min(1.0, fit.scale * fit.scale);
}

}  // namespace

MountReference::MountReference(const std::vector<std::vector<lidar::LidarPoint>>& reference,
                               const Pose3& mount, double coverage_radius_m, double fix_height_m,
                               const MountMonitorConfig& config)
    : config_(config),
      mount_rotation_(mount.to_isometry().linear()),
      radius_m_(coverage_radius_m),
      fix_height_m_(fix_height_m) {
  // Two scales: the fine voxels hold the scene's detail; where a fine voxel holds no plane (a sparse
  // sensor's single ring crossing a facade is a line, whose "normal" is any direction across it), the
  // coarse voxel around it, which spans several rings, holds the facade's true plane.
  const double sizes[kScales] = {config_.voxel_m, config_.voxel_m * config_.coarse_voxel_factor,
                                 config_.voxel_m};
  const double spreads[kScales] = {config_.min_plane_spread, config_.min_plane_spread, 0.0};
  for (int s = 0; s < kScales; ++s) {
    const double size = sizes[s];
    std::unordered_map<std::int64_t, Scatter> cells;
    for (const auto& frame : reference) {
      for (const lidar::LidarPoint& p : frame) {
        const Eigen::Vector3d q = lidar::position_of(p);
        const std::optional<std::int64_t> key = voxel_key(q, size);
        if (!key || q.norm() < config_.min_range_m)
          continue;
        Scatter& c = cells[*key];
        c.sum += q;
        c.outer += q * q.transpose();
        ++c.n;
      }
    }
    // A plane spans its voxel in two directions: the second spread at least min_plane_spread of the
    // voxel's size (a line of points does not say which way its plane faces).
    const double min_spread = std::max(1e-3, spreads[s] * size);
    for (const auto& [key, c] : cells) {
      if (c.n < config_.min_plane_points)
        continue;
      const Eigen::Vector3d mean = c.sum / c.n;
      const Eigen::Matrix3d scatter = c.outer / c.n - mean * mean.transpose();
      const SymmetricEigen3 eigen(scatter);
      const Eigen::Vector3d lambda = eigen.eigenvalues();  // ascending
      if (!(lambda[1] > min_spread * min_spread) || lambda[0] > config_.max_plane_thickness * lambda[1])
        continue;
      planes_[s][key] = Plane{mean.cast<float>(), eigen.eigenvectors().col(0).normalized().cast<float>(),
                              static_cast<float>(std::sqrt(std::max(0.0, lambda[0]))), s == kWeakScale};
    }
    voxel_sizes_[s] = size;
  }
}

const MountReference::Plane* MountReference::plane_at(const Eigen::Vector3d& a) const {
  for (int s = 0; s < kScales; ++s) {
    const std::optional<std::int64_t> key = voxel_key(a, voxel_sizes_[s]);
    if (!key)
      return nullptr;
    const auto it = planes_[s].find(*key);
    if (it != planes_[s].end())
      return &it->second;
  }
  return nullptr;
}

std::vector<PlaneMatch> MountReference::match(const std::vector<Eigen::Vector3d>& points, const Pose3& motion,
                                              double max_residual_m, std::size_t& weak_matches) const {
  const Eigen::Isometry3d t = motion.to_isometry();
  std::vector<PlaneMatch> matches;
  weak_matches = 0;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d a = t * p;
    const Plane* found = plane_at(a);
    if (found == nullptr)
      continue;
    const Plane& plane = *found;
    const Eigen::Vector3d n = plane.normal.cast<double>();
    const Eigen::Vector3d q = plane.point.cast<double>();
    if (std::abs(n.dot(a - q)) > max_residual_m)
      continue;
    if (plane.weak) {
      ++weak_matches;  // on the reference's structure, but its normal says nothing reliable: not fitted
      continue;
    }
    // The sensor's noise along the normal (as rsu-calibrate weighs it) and the plane's own thickness.
    const Eigen::Vector3d beam = a - t.translation();
    const double range = beam.norm();
    const double cos_incidence = std::abs(n.dot(beam)) / range;
    const double sin2 = 1.0 - cos_incidence * cos_incidence;
    const double thickness = static_cast<double>(plane.thickness_m);
    const double sigma = std::sqrt(
        config_.range_sigma_m * config_.range_sigma_m * cos_incidence * cos_incidence +
        range * range * config_.angle_sigma_rad * config_.angle_sigma_rad * sin2 + thickness * thickness);
    matches.push_back(PlaneMatch{p, q, n, sigma});
  }
  return matches;
}

// The step with its components along the directions the scene does not hold removed (solution
// remapping, as for a degenerate scan match): in (dt, r w), metres at the coverage radius, a direction
// whose single-rotation sigma exceeds max_free_sigma is left where the reference has it. Along a street
// of flat facades and thin poles a step there is the noise's (a still VLP-16 had runs of rotations
// 0.4 m off along the street, at a stated sigma of 0.04 m), and a real motion there is not seen at all.
Vector6d MountReference::at_radius_scale() const {
  Vector6d scale;
  scale << 1.0, 1.0, 1.0, radius_m_, radius_m_, radius_m_;
  return scale;
}

Vector6d MountReference::held_step(const PlaneFit& fit) const {
  const Vector6d scale = at_radius_scale();
  const Matrix6d information =
      scale.cwiseInverse().asDiagonal() * stated_information(fit) * scale.cwiseInverse().asDiagonal();
  const SymmetricEigen6 eigen(information);
  const double min_information = 1.0 / (config_.max_free_sigma_m * config_.max_free_sigma_m);
  Vector6d step = scale.asDiagonal() * fit.step;
  for (int k = 0; k < 6; ++k) {
    if (eigen.eigenvalues()[k] >= min_information)
      continue;
    const Vector6d v = eigen.eigenvectors().col(k);
    step -= v.dot(step) * v;
  }
  return scale.cwiseInverse().asDiagonal() * step;
}

MountDrift MountReference::estimate(std::span<const lidar::LidarPoint> rotation, const Pose3& start) const {
  std::vector<Eigen::Vector3d> points;
  const std::size_t stride =
      std::max<std::size_t>(1, rotation.size() / std::max<std::size_t>(1, config_.sample_points));
  for (std::size_t i = 0; i < rotation.size(); i += stride) {
    const lidar::LidarPoint& p = rotation[i];
    const Eigen::Vector3d q = lidar::position_of(p);
    if (q.allFinite() && q.norm() >= config_.min_range_m)
      points.push_back(q);
  }
  MountDrift d;
  Pose3 motion = start;
  PlaneFit fit;
  std::size_t weak = 0;
  d.sampled = points.size();
  d.observable = d.sampled >= config_.min_matches;
  const auto enough = [&](std::size_t matches) {
    return matches >= std::max<double>(static_cast<double>(config_.min_matches),
                                       config_.min_match_fraction * static_cast<double>(d.sampled));
  };
  for (int i = 0; i < config_.iterations && d.observable; ++i) {
    // The gate narrows as the estimate settles: wide enough at first for a bump of a few decimetres.
    const double gate = i == 0 ? config_.max_residual_m : std::min(config_.max_residual_m, 0.25);
    fit = fit_planes(match(points, motion, gate, weak), motion, config_.huber_sigmas);
    if (!enough(fit.matches + weak) || fit.matches < kMinFitted)
      break;
    motion = apply_step(motion, held_step(fit));
    // Converged (a still mount, started from the last estimate, usually after two or three steps):
    // 0.1 mm and 0.0001 deg move a fix at 50 m by less than 0.2 mm.
    if (fit.step.head<3>().norm() < 1e-4 && fit.step.tail<3>().norm() < 2e-6)
      break;
  }
  d.matches = fit.matches;
  d.rms_m = fit.rms_m;
  // What a rotation has matches the reference, but too little of it to tell (a part of a rotation, its
  // other packets lost): unobservable, not a view that no longer matches (which would stop the fixes).
  if (d.observable && !enough(fit.matches + weak) &&
      static_cast<double>(fit.matches + weak) >= config_.min_match_fraction * static_cast<double>(d.sampled))
    d.observable = false;
  d.matches_reference = d.observable && enough(fit.matches + weak);
  d.motion = motion;
  d.covariance = Matrix6d::Identity();  // unknown: metres and radians
  if (d.matches_reference && fit.matches >= kMinFitted) {
    const Eigen::FullPivLU<Matrix6d> lu(stated_information(fit));
    if (lu.isInvertible())
      d.covariance = lu.inverse();
  }
  std::tie(d.error_at_radius_m, d.error_sigma_m) = error_at_radius(motion, d.covariance);
  return d;
}

// A fix is a point at the radius, fix_height_m below the sensor, anywhere around it: the mount's motion
// (t, R) moves it by R p + t - p in the sensor frame, placed in the map by the mount's rotation; the
// largest horizontal part over the azimuths (every 5 deg), and its sigma there: to first order the
// displacement is dt + w x p (point_to_plane.h's perturbation), so its covariance is J C J^T with
// J = [I, -[p]x].
std::pair<double, double> MountReference::error_at_radius(const Pose3& motion,
                                                          const Matrix6d& covariance) const {
  const Eigen::Isometry3d t = motion.to_isometry();
  double worst = 0.0;
  double worst_sigma = 0.0;
  for (int k = 0; k < 72; ++k) {
    const double phi = deg_to_rad(5.0 * k);
    const Eigen::Vector3d map_offset(radius_m_ * std::cos(phi), radius_m_ * std::sin(phi), -fix_height_m_);
    const Eigen::Vector3d p = mount_rotation_.transpose() * map_offset;
    const Eigen::Vector3d moved = mount_rotation_ * (t * p - p);
    const double error = moved.head<2>().norm();
    if (error < worst && k > 0)
      continue;
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>() = Eigen::Matrix3d::Identity();
    j.rightCols<3>() << 0.0, p.z(), -p.y(), -p.z(), 0.0, p.x(), p.y(), -p.x(), 0.0;
    const Eigen::Matrix3d c = mount_rotation_ * j * covariance * j.transpose() * mount_rotation_.transpose();
    const Eigen::Vector2d along =
        error > 1e-12 ? Eigen::Vector2d(moved.head<2>() / error) : Eigen::Vector2d(1, 0);
    worst = error;
    // Along the error where there is one; with none, the larger horizontal variance.
    worst_sigma = std::sqrt(
        std::max(0.0, error > 1e-12 ? along.dot(c.topLeftCorner<2, 2>() * along)
                                    : SymmetricEigen2(c.topLeftCorner<2, 2>()).eigenvalues().maxCoeff()));
  }
  return {worst, worst_sigma};
}

}  // namespace rsu::calibration
