// SPDX-License-Identifier: Apache-2.0
#include "core/grown_footprint.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/symmetric_eigen.h"

namespace rsu::core {

GrownFootprint::GrownFootprint(const tracking::VehicleHypothesis& h, const GatheringConfig& g)
    : centre_(h.centre), yaw_(h.yaw), min_inside_fraction_(g.min_inside_fraction) {
  const SymmetricEigen2 eig(h.covariance.topLeftCorner<2, 2>());
  const double centre_sigma = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
  const double bounded_centre_sigma =
      std::isfinite(centre_sigma) ? std::min(centre_sigma, g.max_margin_m) : g.max_margin_m;
  const double yaw_sigma = std::sqrt(std::max(0.0, h.covariance(2, 2)));
  const double half_diagonal = 0.5 * std::hypot(h.size.length_m, h.size.width_m);
  double margin = g.footprint_sigmas * (centre_sigma + std::min(yaw_sigma, 1.0) * half_diagonal);
  margin = std::isfinite(margin) ? std::clamp(margin, g.min_margin_m, g.max_margin_m) : g.max_margin_m;
  half_ = {0.5 * h.size.length_m + margin, 0.5 * h.size.width_m + margin};
  const double tight_margin = g.min_margin_m + bounded_centre_sigma;
  tight_half_ = {0.5 * h.size.length_m + tight_margin, 0.5 * h.size.width_m + tight_margin};
  lane_half_ = {half_.x(), tight_half_.y()};
  const Eigen::Rotation2Dd r(h.yaw);
  std::size_t k = 0;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      corners_[k] = h.centre + r * Eigen::Vector2d(sx * half_.x(), sy * half_.y());
      tight_corners_[k++] = h.centre + r * Eigen::Vector2d(sx * tight_half_.x(), sy * tight_half_.y());
    }
  }
}

double GrownFootprint::fraction_inside(const perception::Detection& detection,
                                       const Eigen::Vector2d& half) const {
  if (detection.points.empty())  // no points: none inside (never 0 / 0)
    return 0.0;
  const Eigen::Rotation2Dd to_box(-yaw_);
  std::size_t inside = 0;
  for (const Eigen::Vector3d& p : detection.points) {
    const Eigen::Vector2d q = (to_box * (Eigen::Vector2d(p.x(), p.y()) - centre_)).cwiseAbs();
    if (q.x() <= half.x() && q.y() <= half.y())
      ++inside;
  }
  return static_cast<double>(inside) / static_cast<double>(detection.points.size());
}

double GrownFootprint::inside_fraction(const perception::Detection& detection) const {
  return fraction_inside(detection, half_);
}

bool GrownFootprint::tightly_inside(const perception::Detection& detection) const {
  return fraction_inside(detection, tight_half_) >= min_inside_fraction_;
}

bool GrownFootprint::inside_lane(const perception::Detection& detection) const {
  return fraction_inside(detection, lane_half_) >= min_inside_fraction_;
}

bool GrownFootprint::tightly_overlaps(const Eigen::AlignedBox2d& box) const {
  if (box.isEmpty())
    return false;
  // Two rectangles are apart exactly when one of their four edge directions separates them: the map's
  // axes (the footprint's extent on them against the box) and the footprint's own.
  const double c = std::abs(std::cos(yaw_));
  const double s = std::abs(std::sin(yaw_));
  const Eigen::Vector2d extent(c * tight_half_.x() + s * tight_half_.y(),
                               s * tight_half_.x() + c * tight_half_.y());
  if (!Eigen::AlignedBox2d(centre_ - extent, centre_ + extent).intersects(box))
    return false;
  const Eigen::Rotation2Dd to_box(-yaw_);
  Eigen::AlignedBox2d local;
  for (const double x : {box.min().x(), box.max().x()}) {
    for (const double y : {box.min().y(), box.max().y()})
      local.extend(to_box * (Eigen::Vector2d(x, y) - centre_));
  }
  return local.intersects(Eigen::AlignedBox2d(-tight_half_, tight_half_));
}

}  // namespace rsu::core
