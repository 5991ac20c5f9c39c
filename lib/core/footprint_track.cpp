// SPDX-License-Identifier: Apache-2.0
#include "core/footprint_track.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace rsu::core {
namespace {

Eigen::Vector2d across_of(const Eigen::Vector2d& axis) {
  return {-axis.y(), axis.x()};
}

double variance_along(const Eigen::Matrix3d& cov, const Eigen::Vector2d& direction) {
  return std::max(0.0, direction.dot(cov.topLeftCorner<2, 2>() * direction));
}

// The yaw difference a - b folded to (-pi/2, pi/2]: a box has no front.
double axis_difference(double a, double b) {
  double d = std::remainder(a - b, std::numbers::pi);
  return d <= -std::numbers::pi / 2.0 ? d + std::numbers::pi : d;
}

// `fix` moved by `shift` along its length axis, its length-axis variance scaled to `variance` (its
// correlations with the width axis and the yaw kept: a congruence, so it stays positive semi-definite).
void recentre(perception::CorrectedPose& fix, const Eigen::Vector2d& axis, double shift, double variance) {
  fix.pose.x += shift * axis.x();
  fix.pose.y += shift * axis.y();
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  frame.block<2, 1>(0, 0) = axis;
  frame.block<2, 1>(0, 1) = across_of(axis);
  Eigen::Matrix3d local = frame.transpose() * fix.covariance * frame;
  const double scale = local(0, 0) > 0.0 ? std::sqrt(variance / local(0, 0)) : 0.0;
  local.row(0) *= scale;
  local.col(0) *= scale;
  fix.covariance = frame * local * frame.transpose();
}

// How far the vehicle moved between two sweep times by its announced motion (CTRV, the hypothesis
// model), and bounds on that motion's error along and across its heading: the announced speed's error,
// an acceleration since the announcement was made, its heading's error, and a floor.
struct Carry {
  Eigen::Vector2d motion = Eigen::Vector2d::Zero();
  double along_error_m = 0.0;
  double across_error_m = 0.0;
};

Carry carry_of(const v2i::VehicleAnnouncement& a, TimeNs from, TimeNs to,
               const tracking::HypothesisConfig& hypothesis, const FootprintTrackConfig& config) {
  Carry out;
  out.motion = tracking::predict_hypothesis(a, to, hypothesis).centre -
               tracking::predict_hypothesis(a, from, hypothesis).centre;
  const double dt = to_seconds(to - from);
  const double age =
      std::max(std::abs(to_seconds(from - a.generation_time)), std::abs(to_seconds(to - a.generation_time)));
  const double speed_error =
      (config.speed_error_mps + config.speed_error_fraction * std::abs(a.speed_mps.value_or(0.0))) * dt +
      config.max_accel_mps2 * (age + dt) * dt;
  const double length = out.motion.norm();
  out.along_error_m =
      config.motion_floor_m + speed_error + length * (1.0 - std::cos(config.heading_error_rad));
  out.across_error_m = config.motion_floor_m + speed_error + length * std::sin(config.heading_error_rad);
  return out;
}

}  // namespace

FootprintBound bound_of(const perception::CorrectedPose& fix, const FootprintTrackConfig& config) {
  FootprintBound b;
  b.centre = {fix.pose.x, fix.pose.y};
  b.axis = {std::cos(fix.pose.yaw), std::sin(fix.pose.yaw)};
  const double var_along = variance_along(fix.covariance, b.axis);
  double half = 0.0;
  if (fix.length_axis.anchor == perception::AxisAnchor::interval) {
    // The interval is hard (containment); its other terms (noise, shape, the turn of a yaw error) are not.
    const double w = fix.length_axis.interval_m;
    half = w / 2.0 + config.bound_sigmas * std::sqrt(std::max(0.0, var_along - w * w / 12.0));
  } else {
    half = std::max(config.bound_sigmas * std::sqrt(var_along), config.min_bound_half_m);
  }
  b.lo = -half;
  b.hi = half;
  b.across_half_m = config.bound_sigmas * std::sqrt(variance_along(fix.covariance, across_of(b.axis)));
  return b;
}

std::pair<double, double> carried_interval(const FootprintBound& bound, const Eigen::Vector2d& motion,
                                           double along_error_m, double across_error_m,
                                           const Eigen::Vector2d& origin, const Eigen::Vector2d& direction) {
  const double offset = (bound.centre + motion - origin).dot(direction);
  const double c = bound.axis.dot(direction);
  const double s = std::abs(across_of(bound.axis).dot(direction));
  const double spread = (bound.across_half_m + across_error_m) * s + along_error_m * std::abs(c);
  return {offset + std::min(bound.lo * c, bound.hi * c) - spread,
          offset + std::max(bound.lo * c, bound.hi * c) + spread};
}

bool FootprintTracks::chained(const Track& track, const GatheredFix& fix, const v2i::VehicleAnnouncement& a,
                              TimeNs rotation_period) const {
  const TimeNs dt = fix.sweep_time - track.time;
  if (dt < 0 || static_cast<double>(dt) > config_.max_gap_rotations * static_cast<double>(rotation_period))
    return false;
  if (track.size.length_m != a.size.length_m || track.size.width_m != a.size.width_m ||
      track.size.height_m != a.size.height_m)
    return false;
  const perception::CorrectedPose& c = fix.fix.corrected;
  const double turned = a.yaw_rate_rps.value_or(0.0) * to_seconds(dt);
  const double sigma = std::sqrt(track.yaw_sigma * track.yaw_sigma + std::max(0.0, c.covariance(2, 2)));
  const double limit = std::max(config_.min_yaw_jump_rad, config_.yaw_jump_sigmas * sigma);
  return std::abs(axis_difference(c.pose.yaw, track.yaw + turned)) <= limit;
}

void FootprintTracks::combine(GatheredFix& fix, const v2i::VehicleAnnouncement& a, bool assigned,
                              TimeNs rotation_period, double max_sigma_m,
                              const tracking::HypothesisConfig& hypothesis, LidarStats& stats) {
  if (!config_.enabled)
    return;
  perception::CorrectedPose& c = fix.fix.corrected;
  const bool unbounded = fix.outcome == GatheredFixOutcome::correction_failed &&
                         c.status == perception::CorrectionStatus::position_unbounded;
  const bool usable = (fix.ok() || unbounded) && assigned && a.speed_mps && std::isfinite(*a.speed_mps) &&
                      c.covariance.allFinite() && std::isfinite(c.pose.x) && std::isfinite(c.pose.y);
  const auto it = tracks_.find(a.vehicle_id);
  if (!usable) {
    if (it != tracks_.end()) {
      tracks_.erase(it);
      ++stats.track_resets;
    }
    return;
  }
  Track next{bound_of(c, config_), fix.sweep_time, c.pose.yaw, std::sqrt(std::max(0.0, c.covariance(2, 2))),
             a.size};
  // Released twice in one rotation: the later release holds another cluster than the earlier (what lay
  // beside or ahead of it, a neighbour's at 4 m: 1.7 m off across while stating 0.13 m), not another view
  // of the car. Neither is known to be its own: the chain breaks, and neither is kept.
  if (it != tracks_.end() && fix.sweep_time - it->second.time < rotation_period / 2) {
    tracks_.erase(it);
    ++stats.track_resets;
    return;
  }
  if (it == tracks_.end() || !chained(it->second, fix, a, rotation_period)) {
    if (it != tracks_.end())
      ++stats.track_resets;
    tracks_[a.vehicle_id] = next;
    return;
  }
  // The previous bound carried by the vehicle's own motion between the two sweeps, widened by how wrong
  // that motion can be.
  const Track& previous = it->second;
  const Carry carry = carry_of(a, previous.time, fix.sweep_time, hypothesis, config_);
  const Eigen::Vector2d& motion = carry.motion;
  const double along_error = carry.along_error_m;
  const double across_error = carry.across_error_m;
  const auto [carried_lo, carried_hi] =
      carried_interval(previous.bound, motion, along_error, across_error, next.bound.centre, next.bound.axis);
  // Across the length the rotations' bounds must meet too (a neighbour beside it taken for it is 1.5-2 m
  // off across); only the length is cut.
  const auto [across_lo, across_hi] = carried_interval(previous.bound, motion, along_error, across_error,
                                                       next.bound.centre, across_of(next.bound.axis));
  const bool across_met = across_lo <= next.bound.across_half_m && across_hi >= -next.bound.across_half_m;
  const double lo = std::max(carried_lo, next.bound.lo);
  const double hi = std::min(carried_hi, next.bound.hi);
  if (lo > hi || !across_met) {
    // The rotations' bounds exclude each other: one of them is wrong. Nothing sent, nothing kept.
    fix.outcome = GatheredFixOutcome::track_conflict;
    tracks_.erase(it);
    ++stats.track_conflicts;
    return;
  }
  next.bound.lo = lo;
  next.bound.hi = hi;
  it->second = next;  // the intersection, about this rotation's centre
  // An interval-placed centre: the middle of the intersection, a uniform error over it.
  const double variance = (hi - lo) * (hi - lo) / 12.0;
  if (c.length_axis.anchor != perception::AxisAnchor::interval ||
      variance >= variance_along(c.covariance, next.bound.axis))
    return;
  recentre(c, next.bound.axis, 0.5 * (lo + hi), variance);
  if (perception::position_sigma_m(c) > max_sigma_m)
    return;
  if (unbounded) {
    c.status = perception::CorrectionStatus::ok;
    fix.outcome = GatheredFixOutcome::fixed;
    ++stats.track_bounded;
  } else {
    ++stats.track_tightened;
  }
}

void FootprintTracks::reset(LidarStats& stats) {
  stats.track_resets += tracks_.size();
  tracks_.clear();
}

void FootprintTracks::prune(TimeNs oldest) {
  std::erase_if(tracks_, [oldest](const auto& entry) { return entry.second.time < oldest; });
}

}  // namespace rsu::core
