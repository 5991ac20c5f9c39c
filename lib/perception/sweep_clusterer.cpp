// SPDX-License-Identifier: Apache-2.0
#include "perception/sweep_clusterer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/angles.h"
#include "common/rounding.h"

namespace rsu::perception {

namespace {

constexpr double kTwoPi = 2.0 * kPi;

constexpr double kInf = std::numeric_limits<double>::infinity();

bool in_line_of_sight(const ComponentSummary& a, const ComponentSummary& b) {
  return b.min_azimuth <= a.max_azimuth && b.max_azimuth >= a.min_azimuth;
}

}  // namespace

SweepClusterer::SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                               const Eigen::Vector2d& lidar_xy, double rotation_hz,
                               std::span<const double> laser_azimuth_offsets_rad)
    : config_(config),
      clustering_(clustering),
      min_points_(clustering.min_points),
      max_points_(clustering.max_points),
      lidar_xy_(lidar_xy),
      laser_offset_rad_(laser_azimuth_offsets_rad.begin(), laser_azimuth_offsets_rad.end()),
      clusters_(clustering) {
  if (laser_offset_rad_.empty() || !std::all_of(laser_offset_rad_.begin(), laser_offset_rad_.end(),
                                                [](double o) { return std::isfinite(o); })) {
    throw std::invalid_argument("SweepClusterer: the laser azimuth offsets must be finite, one per laser");
  }
  const auto [lo, hi] = std::minmax_element(laser_offset_rad_.begin(), laser_offset_rad_.end());
  if (*hi - *lo > kPi / 2.0) {
    throw std::invalid_argument("SweepClusterer: laser azimuth offsets spread over more than 90 deg");
  }
  // A future point of laser i lands at >= E + o_i: the smallest offset bounds them all.
  lag_rad_ = -*lo;
  init(rotation_hz);
}

SweepClusterer::SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                               const Eigen::Vector2d& lidar_xy, double rotation_hz, double azimuth_spread_rad)
    : config_(config),
      clustering_(clustering),
      min_points_(clustering.min_points),
      max_points_(clustering.max_points),
      lidar_xy_(lidar_xy),
      clusters_(clustering) {
  if (!std::isfinite(azimuth_spread_rad) || azimuth_spread_rad < 0.0 || azimuth_spread_rad > kPi / 2.0) {
    throw std::invalid_argument("SweepClusterer: azimuth spread must be finite, in [0, 90 deg]");
  }
  lag_rad_ = azimuth_spread_rad;
  init(rotation_hz);
}

void SweepClusterer::init(double rotation_hz) {
  if (!(rotation_hz > 0.0) || !std::isfinite(rotation_hz)) {
    throw std::invalid_argument("SweepClusterer: rotation rate must be finite and > 0");
  }
  if (!std::isfinite(config_.release_margin_deg) || config_.release_margin_deg < 0.0 ||
      std::isnan(config_.joint_release_range_gap_m) || config_.joint_release_range_gap_m < 0.0 ||
      !(config_.max_gap_rotations > 0.0) || !lidar_xy_.allFinite()) {
    throw std::invalid_argument("SweepClusterer: margin, gap and LiDAR position must be finite, >= 0");
  }
  radians_per_ns_ = kTwoPi * rotation_hz * 1e-9;
  max_gap_ns_ = static_cast<TimeNs>(config_.max_gap_rotations / rotation_hz * 1e9);
  lag_rad_ += deg_to_rad(config_.release_margin_deg);
}

void SweepClusterer::set_rotation_hz(double rotation_hz) {
  if (!(rotation_hz > 0.0) || !std::isfinite(rotation_hz)) {
    return;
  }
  radians_per_ns_ = kTwoPi * rotation_hz * 1e-9;
  max_gap_ns_ = static_cast<TimeNs>(config_.max_gap_rotations / rotation_hz * 1e9);
}

void SweepClusterer::restart() {
  stats_.points_dropped_restart += clusters_.size();
  clusters_.take_all();
  running_ = false;
  ++stats_.restarts;
}

void SweepClusterer::add(const lidar::LidarPoint& p, bool foreground) {
  ++stats_.points_seen;
  if (!std::isfinite(p.azimuth_rad) || !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    ++stats_.invalid_points;
    return;
  }
  double offset = 0.0;  // beam azimuth - encoder azimuth of this point's laser
  if (!laser_offset_rad_.empty()) {
    if (p.ring >= laser_offset_rad_.size()) {
      ++stats_.invalid_points;
      return;
    }
    offset = laser_offset_rad_[p.ring];
  }
  const double a = wrap_angle_positive(static_cast<double>(p.azimuth_rad));
  if (running_ && (p.time_ns < last_time_ || p.time_ns - last_time_ > max_gap_ns_)) {
    restart();
  }
  if (!running_) {
    running_ = true;
    sweep_ = a - offset;
    last_time_ = p.time_ns;
    const double max_offset = laser_offset_rad_.empty()
                                  ? 0.0
                                  : *std::max_element(laser_offset_rad_.begin(), laser_offset_rad_.end());
    start_u_ = sweep_ + max_offset;
  }
  // Unwrap against where this laser should point by now: robust to lost packets shorter than half a
  // turn.
  const double expected = sweep_ + offset + radians_per_ns_ * static_cast<double>(p.time_ns - last_time_);
  const double u = a + kTwoPi * round_half_away((expected - a) / kTwoPi);
  sweep_ = std::max(sweep_, u - offset);
  last_time_ = p.time_ns;
  if (!foreground) {
    return;
  }
  ++stats_.foreground_points;
  if (!clusters_.accepts(p)) {
    ++stats_.invalid_points;
    return;
  }
  if (clusters_.size() >= config_.max_pending_points) {
    // Drop the oldest (the first arrived: roughly the smallest azimuth). Rare: only a foreground
    // flood. What remains is clustered again, as dropping part of a component may split it.
    const std::size_t n = std::max<std::size_t>(1, clusters_.size() / 8);
    const std::vector<PendingPoint> pending = clusters_.take_all();
    for (std::size_t i = n; i < pending.size(); ++i)
      clusters_.add(pending[i]);
    stats_.points_dropped_overflow += n;
  }
  PendingPoint pending{.point = p, .azimuth = u, .seq = next_seq_++};
  pending.range =
      std::hypot(static_cast<double>(p.x) - lidar_xy_.x(), static_cast<double>(p.y) - lidar_xy_.y());
  // The closing rule of the file comment for this point: r sin(a_future - u) > d once a_future is past
  // u + asin(d / r); never while r <= d.
  const double tolerance = clustering_.tolerance_m;
  pending.close_at = pending.range > tolerance ? u + std::asin(tolerance / pending.range) : kInf;
  clusters_.add(pending);
}

bool SweepClusterer::cut_at_start(std::span<const PendingPoint> members) const {
  // The mirror of the closing rule: a point nearer the start line than the clustering tolerance may
  // have neighbours that went by before the stream began.
  for (const PendingPoint& m : members) {
    const double ahead = m.azimuth - start_u_;
    if (ahead >= kPi / 2.0) {
      continue;
    }
    if (ahead <= 0.0 || m.range * std::sin(ahead) <= clustering_.tolerance_m) {
      return true;
    }
  }
  return false;
}

void SweepClusterer::drop_stale() {
  const double oldest_allowed = sweep_ - kPi;
  const auto components = clusters_.components();
  if (std::none_of(components.begin(), components.end(),
                   [&](std::uint32_t c) { return clusters_.summary(c).min_azimuth < oldest_allowed; })) {
    return;
  }
  // Rare (points within the tolerance of the LiDAR itself): dropping part of a component may split
  // it, so what remains is clustered again.
  for (const PendingPoint& m : clusters_.take_all()) {
    if (m.azimuth < oldest_allowed)
      ++stats_.points_dropped_stale;
    else
      clusters_.add(m);
  }
}

std::vector<SweptCluster> SweepClusterer::release_closed(std::span<const OpenClusterName> fixed_open) {
  return release(false, fixed_open);
}

std::vector<SweptCluster> SweepClusterer::release_all() {
  return release(true, {});
}

std::vector<std::vector<lidar::LidarPoint>> SweepClusterer::overtaken_open_points() {
  std::vector<std::vector<lidar::LidarPoint>> out;
  if (overtaken_.empty())
    return out;
  std::vector<std::uint64_t> still_open;
  for (const std::uint32_t c : clusters_.components()) {
    const std::uint64_t seq = clusters_.summary(c).first_seq;
    if (std::find(overtaken_.begin(), overtaken_.end(), seq) == overtaken_.end())
      continue;
    still_open.push_back(seq);
    std::vector<lidar::LidarPoint>& points = out.emplace_back();
    for (const PendingPoint& m : clusters_.copy(c))
      points.push_back(m.point);
  }
  overtaken_ = std::move(still_open);
  return out;
}

std::vector<SweptCluster> SweepClusterer::swept_open() {
  std::vector<SweptCluster> out;
  const double a_future = sweep_ - lag_rad_;
  std::vector<std::uint64_t> given;  // those still pending
  for (const std::uint32_t c : clusters_.components()) {
    const ComponentSummary& s = clusters_.summary(c);
    const bool before =
        std::find(swept_open_given_.begin(), swept_open_given_.end(), s.first_seq) != swept_open_given_.end();
    if (before)
      given.push_back(s.first_seq);
    if (before || a_future > s.close_at || !(a_future > s.max_azimuth) || s.size < min_points_ ||
        s.size > max_points_)
      continue;
    given.push_back(s.first_seq);
    const std::vector<PendingPoint> members = clusters_.copy(c);
    if (cut_at_start(members))
      continue;
    SweptCluster cluster;
    cluster.id = s.first_seq;
    cluster.points.reserve(members.size());
    for (const PendingPoint& m : members)
      cluster.points.push_back(m.point);
    out.push_back(std::move(cluster));
  }
  swept_open_given_ = std::move(given);
  return out;
}

SweptCluster SweepClusterer::released(const ComponentSummary& s, std::span<const ComponentSummary> open,
                                      std::span<const PendingPoint> members) {
  // Released ahead of nearer open clusters in its line of sight: they become its occluders
  // (overtaken_open_points), and it may continue behind them. Only for clusters released, not dropped.
  SweptCluster cluster;
  cluster.id = s.first_seq;
  for (const ComponentSummary& o : open) {
    if (!in_line_of_sight(s, o))
      continue;
    // One it did not wait for, farther within the gap: what it holds so far (a fragment of the same
    // vehicle if it lies in its footprint, core/vehicle_gatherer.h).
    if (o.min_range >= s.min_range && o.min_range - s.max_range < config_.joint_release_range_gap_m)
      cluster.open_beyond.push_back(o.box);
    if (!(o.min_range < s.max_range))
      continue;
    cluster.ahead_of_open = true;
    if (std::find(overtaken_.begin(), overtaken_.end(), o.first_seq) == overtaken_.end())
      overtaken_.push_back(o.first_seq);
  }
  cluster.points.reserve(members.size());
  for (const PendingPoint& m : members)
    cluster.points.push_back(m.point);
  return cluster;
}

std::vector<SweptCluster> SweepClusterer::release(bool everything,
                                                  std::span<const OpenClusterName> fixed_open) {
  std::vector<SweptCluster> out;
  if (!everything) {
    drop_stale();
  }
  if (clusters_.size() == 0) {
    // Nothing pending: bring the unwrapped sweep back near [0, 2 pi) so it never loses precision
    // (the start line, once a whole turn behind, no longer cuts anything).
    const double shift = sweep_ - std::fmod(sweep_, kTwoPi);
    start_u_ = sweep_ - start_u_ > kTwoPi ? -kInf : start_u_ - shift;
    sweep_ -= shift;
    return out;
  }
  // Closed: no later point can join (file comment); at the end of the stream, every component.
  const double a_future = sweep_ - lag_rad_;
  std::vector<std::uint32_t> closed;
  std::vector<ComponentSummary> open;  // copies: take() below changes the components
  // An open one named in `fixed_open`, unchanged and swept by every laser, goes with them (header).
  const auto fixed = [&](const ComponentSummary& s) {
    return a_future > s.max_azimuth &&
           std::any_of(fixed_open.begin(), fixed_open.end(),
                       [&](const OpenClusterName& n) { return n.id == s.first_seq && n.size == s.size; });
  };
  for (const std::uint32_t c : clusters_.components()) {
    const ComponentSummary& s = clusters_.summary(c);
    if (everything || a_future > s.close_at || fixed(s))
      closed.push_back(c);
    else
      open.push_back(s);
  }
  if (closed.empty()) {
    return out;
  }
  std::sort(closed.begin(), closed.end(), [&](std::uint32_t a, std::uint32_t b) {
    return clusters_.summary(a).first_seq < clusters_.summary(b).first_seq;
  });
  for (const std::uint32_t c : closed) {
    const ComponentSummary s = clusters_.summary(c);  // a copy: take() below removes the component
    // Waits for an open cluster in its line of sight that starts nearer, within the gap (file comment).
    const bool waits = std::any_of(open.begin(), open.end(), [&](const ComponentSummary& o) {
      return in_line_of_sight(s, o) && o.min_range < s.min_range &&
             s.min_range - o.max_range < config_.joint_release_range_gap_m;
    });
    if (waits)
      continue;
    const std::vector<PendingPoint> members = clusters_.take(c);
    if (cut_at_start(members)) {
      ++stats_.clusters_dropped_cut_at_start;
      continue;
    }
    if (members.size() < min_points_) {
      ++stats_.clusters_dropped_small;
      continue;
    }
    if (members.size() > max_points_) {
      ++stats_.clusters_dropped_large;
      continue;
    }
    SweptCluster cluster = released(s, open, members);
    out.push_back(std::move(cluster));
    ++stats_.clusters_released;
    if (!everything && !(a_future > s.close_at))
      ++stats_.clusters_released_open;  // not closed: named in fixed_open
  }
  return out;
}

}  // namespace rsu::perception
