// SPDX-License-Identifier: Apache-2.0
#include "ros/base_link_pose.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstdlib>

#include "common/angles.h"
#include "fusion/measurement_model.h"

namespace rsu::ros {
namespace {

// Rows/columns of (x, y, yaw) in ROS's 6x6 (x, y, z, roll, pitch, yaw).
constexpr std::array<std::size_t, 3> kPlanar = {0, 1, 5};

Eigen::Matrix3d planar_covariance(const RosPoseWithCovariance& p) {
  Eigen::Matrix3d c;
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j)
      c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          p.covariance[kPlanar[i] * 6 + kPlanar[j]];
  }
  return c;
}

bool is_well_formed(const RosPoseWithCovariance& p) {
  for (const double v : p.position)
    if (!std::isfinite(v))
      return false;
  double norm2 = 0.0;
  for (const double v : p.orientation) {
    if (!std::isfinite(v))
      return false;
    norm2 += v * v;
  }
  if (std::abs(norm2 - 1.0) > 1e-3)
    return false;
  const Eigen::Matrix3d c = planar_covariance(p);
  if (!c.allFinite() || !c.isApprox(c.transpose(), 1e-9))
    return false;
  return Eigen::LLT<Eigen::Matrix3d>(c).info() == Eigen::Success;
}

const StampedPose* nearest_in_time(TimeNs t, std::span<const StampedPose> poses) {
  const StampedPose* best = nullptr;
  for (const StampedPose& p : poses) {
    if (best == nullptr || std::llabs(p.stamp - t) < std::llabs(best->stamp - t))
      best = &p;
  }
  return best;
}

}  // namespace

std::string_view refusal_name(BaseLinkRefusal refusal) {
  switch (refusal) {
    case BaseLinkRefusal::kNone:
      return "none";
    case BaseLinkRefusal::kMalformedFix:
      return "malformed_fix";
    case BaseLinkRefusal::kNoOwnPose:
      return "no_own_pose";
    case BaseLinkRefusal::kHeadingDisagreement:
      return "heading_disagreement";
    case BaseLinkRefusal::kCount:
      break;
  }
  return "unknown";
}

double yaw_of(const std::array<double, 4>& q) {
  const auto [x, y, z, w] = q;
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

BaseLinkResult base_link_pose(const StampedPose& fix, std::span<const StampedPose> own,
                              const BaseLinkConfig& config) {
  BaseLinkResult out;
  if (!is_well_formed(fix.pose)) {
    out.refusal = BaseLinkRefusal::kMalformedFix;
    return out;
  }
  const StampedPose* mine = nearest_in_time(fix.stamp, own);
  if (mine == nullptr ||
      std::llabs(mine->stamp - fix.stamp) > static_cast<TimeNs>(config.max_own_pose_age_s * 1e9)) {
    out.refusal = BaseLinkRefusal::kNoOwnPose;
    return out;
  }
  const double heading = yaw_of(mine->pose.orientation);
  out.yaw_disagreement_rad =
      fusion::yaw_residual(yaw_of(fix.pose.orientation), heading, fusion::MeasurementSource::kRsu);
  if (std::abs(out.yaw_disagreement_rad) > config.max_heading_disagreement_rad) {
    out.refusal = BaseLinkRefusal::kHeadingDisagreement;
    return out;
  }
  // The box yaw on the heading's branch: the vehicle's yaw as the RSU measured it.
  const double yaw = wrap_angle(heading + out.yaw_disagreement_rad);
  const Eigen::Vector2d& o = config.base_link_offset;
  // base_link = centre + R(yaw) o, i.e. the box centre of a "reference point" at the centre whose offset is
  // -o.
  const Eigen::Vector2d base =
      fusion::box_centre_from_reference(fix.pose.position[0], fix.pose.position[1], yaw, -o);
  // d(base)/d(centre x, centre y, yaw): identity, and d(R(yaw) o)/d(yaw) in the yaw column.
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Identity();
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  jacobian(0, 2) = -s * o.x() - c * o.y();
  jacobian(1, 2) = c * o.x() - s * o.y();
  const Eigen::Matrix3d planar = jacobian * planar_covariance(fix.pose) * jacobian.transpose();

  RosPoseWithCovariance& p = out.pose;
  p.position = {base.x(), base.y(), mine->pose.position[2]};
  p.orientation = {0.0, 0.0, std::sin(yaw / 2), std::cos(yaw / 2)};
  p.covariance.fill(0.0);
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j)
      p.covariance[kPlanar[i] * 6 + kPlanar[j]] =
          planar(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  }
  p.covariance[2 * 6 + 2] = mine->pose.covariance[2 * 6 + 2];
  p.covariance[3 * 6 + 3] = kUnknownVariance;
  p.covariance[4 * 6 + 4] = kUnknownVariance;
  return out;
}

}  // namespace rsu::ros
