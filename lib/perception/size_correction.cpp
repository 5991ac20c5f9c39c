// SPDX-License-Identifier: Apache-2.0
// Algorithm 1 of the paper, as written, plus the names of the correction enums.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/symmetric_eigen.h"
#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

// A box has no front: fold a direction into (-pi/2, pi/2].
double fold_half_turn(double a) {
  a = std::remainder(a, std::numbers::pi);
  return a <= -std::numbers::pi / 2.0 ? a + std::numbers::pi : a;
}

// Packets were lost while the sweep passed the vehicle (LidarGeometry::complete_sweep): any part of it
// may be missing, so its points bound its place only by containment. Such a fix is sent only when that
// still places it within this (rsud's fault test, 5 % packet loss: such fixes were 0.23-0.66 m off,
// where every fix of a complete sweep was within 0.1 m).
constexpr double kMaxPositionSigmaIncompleteSweepM = 0.1;

}  // namespace

double position_sigma_m(const CorrectedPose& fix) {
  // A covariance that is not a number bounds nothing: unbounded, never 0 (std::max(0, NaN) is 0), so that
  // every cap refuses it.
  if (!fix.covariance.topLeftCorner<2, 2>().allFinite())
    return std::numeric_limits<double>::infinity();
  const SymmetricEigen2 eig(fix.covariance.topLeftCorner<2, 2>());
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

double max_position_sigma_m(bool complete_sweep, const CorrectionConfig& config) {
  return complete_sweep ? config.max_position_sigma_m : kMaxPositionSigmaIncompleteSweepM;
}

bool valid_size(const VehicleSize& size) {
  return std::isfinite(size.length) && std::isfinite(size.width) && size.length > 0.0 && size.width > 0.0;
}

double lower_body_height(const VehicleSize& size, const CorrectionConfig& config) {
  if (!(std::isfinite(size.height) && size.height > 0.0))
    return std::numeric_limits<double>::infinity();
  return config.lower_body_fraction * size.height;
}

double side_body_height(const VehicleSize& size, const CorrectionConfig& config) {
  return std::max(lower_body_height(size, config), config.full_plan_height_m);
}

double end_body_height(const VehicleSize& size, const CorrectionConfig& config) {
  const double lower = lower_body_height(size, config);
  return std::isfinite(lower) ? std::min(lower, config.max_end_body_height_m) : lower;
}

double surely_bonnet_high(double end_height, const CorrectionConfig& config) {
  return end_height < config.max_end_body_height_m ? std::min(end_height, config.min_bonnet_height_m)
                                                   : end_height;
}

std::string_view to_string(CorrectionStatus status) {
  switch (status) {
    case CorrectionStatus::ok:
      return "ok";
    case CorrectionStatus::no_fit:
      return "no_fit";
    case CorrectionStatus::invalid_size:
      return "invalid_size";
    case CorrectionStatus::invalid_input:
      return "invalid_input";
    case CorrectionStatus::inconsistent_box:
      return "inconsistent_box";
    case CorrectionStatus::yaw_unobserved:
      return "yaw_unobserved";
    case CorrectionStatus::position_unbounded:
      return "position_unbounded";
  }
  return "unknown";
}

std::string_view to_string(AmbiguityResolution resolution) {
  switch (resolution) {
    case AmbiguityResolution::edge_lengths:
      return "edge_lengths";
    case AmbiguityResolution::prior:
      return "prior";
    case AmbiguityResolution::geometry:
      return "geometry";
    case AmbiguityResolution::unresolved:
      return "unresolved";
  }
  return "unknown";
}

CorrectedPose correct_algorithm1(const RectangleFit& fit, const VehicleSize& size,
                                 const Eigen::Vector2d& lidar_xy, const CovarianceModelConfig& covariance) {
  CorrectedPose out;
  if (!fit.ok()) {
    out.status = CorrectionStatus::no_fit;
    return out;
  }
  if (!valid_size(size)) {
    out.status = CorrectionStatus::invalid_size;
    return out;
  }
  if (!lidar_xy.allFinite()) {
    out.status = CorrectionStatus::invalid_input;
    return out;
  }

  // P <- nearest vertex in B to M (the alignment point); Pl, Pr <- its two adjacent vertices.
  std::size_t k = 0;
  for (std::size_t i = 1; i < 4; ++i) {
    if ((fit.corners[i] - lidar_xy).norm() < (fit.corners[k] - lidar_xy).norm()) {
      k = i;
    }
  }
  const std::size_t k_left = (k + 3) % 4;
  const std::size_t k_right = (k + 1) % 4;
  const Eigen::Vector2d& p = fit.corners[k];
  const Eigen::Vector2d& pl = fit.corners[k_left];
  const Eigen::Vector2d& pr = fit.corners[k_right];
  const Eigen::Vector2d l = (pl - p).normalized();
  const Eigen::Vector2d r = (pr - p).normalized();

  // Edge k runs from P along R, edge k_left from Pl to P along L. The face through P perpendicular to
  // an axis is the edge running along the other axis.
  const RectangleEdge& edge_along_r = fit.edges[k];
  const RectangleEdge& edge_along_l = fit.edges[k_left];
  auto axis_evidence = [](const RectangleEdge& face) {
    return face.seen ? AxisEvidence{AxisAnchor::face, face.support_points}
                     : AxisEvidence{AxisAnchor::one_end, 0};
  };

  Eigen::Vector2d c;
  Eigen::Vector2d length_dir;
  FixEvidence evidence;
  if ((pl - p).norm() < (pr - p).norm()) {
    c = p + (l * size.width + r * size.length) / 2.0;
    length_dir = r;
    evidence.length_axis = axis_evidence(edge_along_l);
    evidence.width_axis = axis_evidence(edge_along_r);
  } else {
    c = p + (r * size.width + l * size.length) / 2.0;
    length_dir = l;
    evidence.length_axis = axis_evidence(edge_along_r);
    evidence.width_axis = axis_evidence(edge_along_l);
  }

  out.status = CorrectionStatus::ok;
  out.pose.x = c.x();
  out.pose.y = c.y();
  out.pose.yaw = fold_half_turn(std::atan2(length_dir.y(), length_dir.x()));
  out.resolution = AmbiguityResolution::edge_lengths;
  out.confidence = 1.0;  // Algorithm 1 does not assess its assignment
  out.alignment_point = p;

  evidence.range_m = (p - lidar_xy).norm();
  evidence.yaw = out.pose.yaw;
  evidence.lever = c - p;
  std::size_t f = 0;
  for (std::size_t i = 0; i < 4 && f < 2; ++i) {
    if (fit.edges[i].seen) {
      evidence.seen_faces[f++] = face_evidence(fit, i, lidar_xy);
    }
  }
  out.covariance = fix_covariance(evidence, covariance);
  return out;
}

}  // namespace rsu::perception
