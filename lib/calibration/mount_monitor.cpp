// SPDX-License-Identifier: Apache-2.0
#include "calibration/mount_monitor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "calibration/coarse_search.h"
#include "common/angles.h"
#include "common/symmetric_eigen.h"

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

std::string drift_text(const MountDrift& d, double tolerance_m) {
  char text[320];
  std::snprintf(text, sizeof text,
                "moved by (%.3f, %.3f, %.3f) m, roll %.3f, pitch %.3f, yaw %.3f deg since its reference: "
                "%.3f m at the coverage radius (tolerance %.3f m; %zu points matched, rms %.3f m)",
                d.motion.x, d.motion.y, d.motion.z, rad_to_deg(d.motion.roll), rad_to_deg(d.motion.pitch),
                rad_to_deg(d.motion.yaw), d.error_at_radius_m, tolerance_m, d.matches, d.rms_m);
  if (d.rotations_averaged < 2)
    return text;
  char averaged[96];
  std::snprintf(averaged, sizeof averaged, "; its weakly held directions the mean of %d rotations",
                d.rotations_averaged);
  return text + std::string(averaged);
}

}  // namespace

MountMonitor::MountMonitor(const std::vector<std::vector<lidar::LidarPoint>>& reference, const Pose3& mount,
                           double coverage_radius_m, double fix_height_m, const MountMonitorConfig& config)
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
        const Eigen::Vector3d q(p.x, p.y, p.z);
        if (!has_voxel_key(q, size) || q.norm() < config_.min_range_m)
          continue;
        Scatter& c = cells[voxel_key(q, size)];
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

const MountMonitor::Plane* MountMonitor::plane_at(const Eigen::Vector3d& a) const {
  for (int s = 0; s < kScales; ++s) {
    if (!has_voxel_key(a, voxel_sizes_[s]))
      return nullptr;
    const auto it = planes_[s].find(voxel_key(a, voxel_sizes_[s]));
    if (it != planes_[s].end())
      return &it->second;
  }
  return nullptr;
}

std::vector<PlaneMatch> MountMonitor::match(const std::vector<Eigen::Vector3d>& points, const Pose3& motion,
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
    const double thickness = plane.thickness_m;
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
Vector6d MountMonitor::at_radius_scale() const {
  Vector6d scale;
  scale << 1.0, 1.0, 1.0, radius_m_, radius_m_, radius_m_;
  return scale;
}

Vector6d MountMonitor::held_step(const PlaneFit& fit) const {
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

MountDrift MountMonitor::estimate(std::span<const lidar::LidarPoint> rotation, const Pose3& start) const {
  std::vector<Eigen::Vector3d> points;
  const std::size_t stride =
      std::max<std::size_t>(1, rotation.size() / std::max<std::size_t>(1, config_.sample_points));
  for (std::size_t i = 0; i < rotation.size(); i += stride) {
    const lidar::LidarPoint& p = rotation[i];
    const Eigen::Vector3d q(p.x, p.y, p.z);
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
std::pair<double, double> MountMonitor::error_at_radius(const Pose3& motion,
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

bool MountMonitor::check_rotation(std::span<const lidar::LidarPoint> rotation, TimeNs time) {
  if (!config_.enabled)
    return false;
  if (++stats_.rotations_checked == 1)
    first_checked_ = time;
  // Every rotation is registered from the reference itself, not from the last estimate: along a
  // direction the scene holds weakly (a street of flat facades) an estimate started from the last one
  // keeps whatever it had there and adds its own noise, a random walk that wandered 6 cm from a still
  // mount in a minute (a false stop); from the reference, each rotation's noise is its own.
  const MountDrift drift = estimate(rotation, Pose3{});
  if (!drift.observable) {
    ++stats_.rotations_unobservable;  // too few static points to tell: nothing decided
    return false;
  }
  // The evidence over the window: the rotations that match the reference (a rewound clock starts afresh).
  if (drift.matches_reference) {
    if (!recent_.empty() && time < recent_.back().time)
      recent_.clear();
    recent_.push_back(Evidence{time, drift.motion, drift.covariance});
    while (recent_.size() > kMaxAveraged || time - recent_.front().time >= config_.weak_evidence_window)
      recent_.pop_front();
  }
  last_ = drift.matches_reference ? decide(drift) : drift;
  const double tolerance = config_.max_position_error_m;
  const double margin = config_.significance_sigmas * last_.error_sigma_m;
  // The scene cannot verify the tolerance when 3 sigma of the error alone exceed it (header).
  const bool unverifiable = last_.matches_reference && margin > tolerance;
  // Beyond the tolerance even with the weakly held directions' mean taken significance_sigmas of its
  // sigma towards the reference: what those directions say must be significant (their rotations' spread
  // is wider than stated, and a rotation missing packets shifts them: a still OS1-128's mean of 18
  // rotations read 5.3 cm at a scaled sigma of 1.5 cm through rsud on a loaded machine). The directions
  // one rotation pins down well keep the rule: their estimate beyond the tolerance, significant or not.
  const bool beyond = !last_.matches_reference ||
                      last_.error_at_radius_m - config_.significance_sigmas * last_.weak_sigma_m > tolerance;
  if (!last_.matches_reference)
    ++stats_.rotations_mismatched;
  if (beyond)
    ++stats_.rotations_beyond_tolerance;
  within_run_ = beyond ? 0 : within_run_ + 1;
  // Directions held while the window's mean gathers evidence along them (start-up) do not say yet that
  // the scene cannot verify the tolerance.
  const bool gathering = last_.weak_held && time - first_checked_ < config_.weak_evidence_window;
  if (unverifiable && !gathering) {
    ++stats_.rotations_unverifiable;
    if (!warned_unverifiable_) {
      warned_unverifiable_ = true;
      char text[320];
      std::snprintf(
          text, sizeof text,
          "the scene holds the LiDAR too weakly to verify its mount to %.3f m at the coverage radius "
          "(sigma %.3f m there): fixes stop on the estimate alone, beyond the tolerance, "
          "significant or not",
          tolerance, last_.error_sigma_m);
      notice_ = text;
      if (state_ == MountState::kServing && !beyond)
        return true;
    }
  }
  // Confirmed: beyond by 3 sigma, in a scene that can verify the tolerance at all (where it cannot, its
  // sigma is not to be trusted either: a still VLP-16 between two facades had single rotations 0.4 m
  // off along the street at a stated 0.04 m).
  const bool significant = !unverifiable && last_.error_at_radius_m - margin > tolerance;
  // An estimate beyond the tolerance but not significantly: a weak direction's noise, or a real motion
  // the scene cannot confirm. Withheld once it has persisted over suspect_rotations in a row.
  suspect_run_ = beyond && !significant ? suspect_run_ + 1 : 0;
  if (state_ == MountState::kServing) {
    if (!beyond || (last_.matches_reference && !significant && suspect_run_ < config_.suspect_rotations))
      return false;
    stop(significant);
    return true;
  }
  // Back within resume_fraction of the tolerance by 3 sigma. Where the scene cannot verify the tolerance
  // the fixes stay withheld until a recalibration (a new mount, a new monitor): an estimate that reads
  // calm there may be one that does not see the motion at all.
  return resume_when_calm(!unverifiable && last_.matches_reference &&
                              last_.error_at_radius_m + margin <= config_.resume_fraction * tolerance,
                          time);
}

void MountMonitor::stop(bool significant) {
  state_ = MountState::kMoved;
  stopped_by_ = last_;
  calm_ = false;
  suspect_run_ = 0;
  ++stats_.stops;
  if (!last_.matches_reference) {
    cause_ = StopCause::kMismatch;
    reason_ = "the LiDAR's view no longer matches its reference (" + std::to_string(last_.matches) + " of " +
              std::to_string(last_.sampled) + " static points matched): moved far";
  } else if (significant) {
    cause_ = StopCause::kMoved;
    reason_ = "the LiDAR " + drift_text(last_, config_.max_position_error_m);
  } else {
    cause_ = StopCause::kSuspected;
    ++stats_.stops_unconfirmed;
    char sigma[96];
    std::snprintf(sigma, sizeof sigma, " [not confirmed: sigma %.3f m at the radius]", last_.error_sigma_m);
    reason_ = "the LiDAR may have " + drift_text(last_, config_.max_position_error_m) + sigma;
  }
  notice_ = "fixes stopped: " + reason_ + ". Recalibrate (rsu-calibrate) and give rsud the new mount";
}

bool MountMonitor::resume_when_calm(bool calm, TimeNs time) {
  if (!calm) {
    calm_ = false;
    return false;
  }
  if (!calm_) {
    calm_ = true;
    calm_since_ = time;
  }
  if (time - calm_since_ < config_.resume_after)
    return false;
  state_ = MountState::kServing;
  cause_ = StopCause::kNone;
  ++stats_.resumes;
  notice_ = "fixes resumed: the LiDAR is back within tolerance (" +
            drift_text(last_, config_.max_position_error_m) + ")";
  reason_.clear();
  return true;
}

}  // namespace rsu::calibration
