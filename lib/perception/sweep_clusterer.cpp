// SPDX-License-Identifier: Apache-2.0
#include "perception/sweep_clusterer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::perception {

namespace {

constexpr double kTwoPi = 2.0 * kPi;

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

SweepClusterer::SweepClusterer(const SweepConfig& config, const perception::ClusteringConfig& clustering,
                               const Eigen::Vector2d& lidar_xy, double rotation_hz,
                               std::span<const double> laser_azimuth_offsets_rad)
    : config_(config),
      clustering_(clustering),
      min_points_(clustering.min_points),
      max_points_(clustering.max_points),
      lidar_xy_(lidar_xy),
      laser_offset_rad_(laser_azimuth_offsets_rad.begin(), laser_azimuth_offsets_rad.end()) {
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
      lidar_xy_(lidar_xy) {
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
      !(config_.max_gap_rotations > 0.0) || !lidar_xy_.allFinite()) {
    throw std::invalid_argument("SweepClusterer: margin, gap and LiDAR position must be finite, >= 0");
  }
  clustering_.min_points = 1;  // every component is returned so that noise can be released (and dropped)
  clustering_.max_points = std::numeric_limits<std::size_t>::max();
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
  stats_.points_dropped_restart += points_.size();
  points_.clear();
  azimuth_.clear();
  range_.clear();
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
  const double u = a + kTwoPi * std::round((expected - a) / kTwoPi);
  sweep_ = std::max(sweep_, u - offset);
  last_time_ = p.time_ns;
  if (!foreground) {
    return;
  }
  ++stats_.foreground_points;
  if (points_.size() >= config_.max_pending_points) {
    // Drop the oldest (the front is roughly the smallest azimuth). Rare: only a foreground flood.
    const std::size_t n = std::max<std::size_t>(1, points_.size() / 8);
    points_.erase(points_.begin(), points_.begin() + static_cast<std::ptrdiff_t>(n));
    azimuth_.erase(azimuth_.begin(), azimuth_.begin() + static_cast<std::ptrdiff_t>(n));
    range_.erase(range_.begin(), range_.begin() + static_cast<std::ptrdiff_t>(n));
    stats_.points_dropped_overflow += n;
  }
  points_.push_back(p);
  azimuth_.push_back(u);
  range_.push_back(
      std::hypot(static_cast<double>(p.x) - lidar_xy_.x(), static_cast<double>(p.y) - lidar_xy_.y()));
}

std::vector<SweepClusterer::ComponentState> SweepClusterer::component_states(const Clustering& components,
                                                                             double a_future) const {
  const double tolerance = clustering_.tolerance_m;
  std::vector<ComponentState> state(components.clusters.size());
  for (std::size_t c = 0; c < components.clusters.size(); ++c) {
    ComponentState& s = state[c];
    for (const std::uint32_t i : components.clusters[c]) {
      s.min_u = std::min(s.min_u, azimuth_[i]);
      s.max_u = std::max(s.max_u, azimuth_[i]);
      if (s.closed && a_future != -kInf) {
        const double behind = a_future - azimuth_[i];
        const double distance = behind <= 0.0         ? 0.0
                                : behind >= kPi / 2.0 ? range_[i]
                                                      : range_[i] * std::sin(behind);
        s.closed = distance > tolerance;
      }
    }
  }
  return state;
}

bool SweepClusterer::cut_at_start(const Cluster& members) const {
  // The mirror of the closing rule (component_states): a point nearer the start line than the
  // clustering tolerance may have neighbours that went by before the stream began.
  for (const std::uint32_t i : members) {
    const double ahead = azimuth_[i] - start_u_;
    if (ahead >= kPi / 2.0) {
      continue;
    }
    if (ahead <= 0.0 || range_[i] * std::sin(ahead) <= clustering_.tolerance_m) {
      return true;
    }
  }
  return false;
}

void SweepClusterer::drop_stale() {
  const double oldest_allowed = sweep_ - kPi;
  compact_pending([&](std::size_t i) {
    const bool stale = azimuth_[i] < oldest_allowed;
    stats_.points_dropped_stale += stale ? 1 : 0;
    return stale;
  });
}

std::vector<SweptCluster> SweepClusterer::release_closed() {
  return release(false);
}

std::vector<SweptCluster> SweepClusterer::release_all() {
  return release(true);
}

std::vector<SweptCluster> SweepClusterer::release(bool everything) {
  std::vector<SweptCluster> out;
  if (!everything) {
    drop_stale();
  }
  if (points_.empty()) {
    // Nothing pending: bring the unwrapped sweep back near [0, 2 pi) so it never loses precision
    // (the start line, once a whole turn behind, no longer cuts anything).
    const double shift = sweep_ - std::fmod(sweep_, kTwoPi);
    start_u_ = sweep_ - start_u_ > kTwoPi ? -kInf : start_u_ - shift;
    sweep_ -= shift;
    return out;
  }
  const double a_future = sweep_ - lag_rad_;
  if (!everything) {
    // Cheap exit for the common case (a packet that closes nothing): no point is behind a_future.
    const double min_u = *std::min_element(azimuth_.begin(), azimuth_.end());
    if (min_u >= a_future) {
      return out;
    }
  }

  std::vector<std::uint32_t> all(points_.size());
  std::iota(all.begin(), all.end(), 0U);
  const Clustering components = cluster_grid(points_, all, clustering_);
  const std::vector<ComponentState> state = component_states(components, everything ? -kInf : a_future);

  std::vector<bool> take(points_.size(), false);
  for (std::size_t c = 0; c < components.clusters.size(); ++c) {
    if (!state[c].closed) {
      continue;
    }
    bool overlaps_open = false;
    for (std::size_t o = 0; o < components.clusters.size() && !overlaps_open; ++o) {
      overlaps_open =
          !state[o].closed && state[o].min_u <= state[c].max_u && state[o].max_u >= state[c].min_u;
    }
    if (overlaps_open) {
      continue;
    }
    const Cluster& members = components.clusters[c];
    for (const std::uint32_t i : members) {
      take[i] = true;
    }
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
    SweptCluster cluster;
    cluster.points.reserve(members.size());
    for (const std::uint32_t i : members) {
      cluster.points.push_back(points_[i]);
    }
    out.push_back(std::move(cluster));
    ++stats_.clusters_released;
  }
  // Points cluster_grid refused (none should remain: every pending point is finite) are left pending
  // and age out as stale.
  compact_pending([&](std::size_t i) { return static_cast<bool>(take[i]); });
  if (everything) {
    stats_.invalid_points += points_.size();
    points_.clear();
    azimuth_.clear();
    range_.clear();
  }
  return out;
}

}  // namespace rsu::perception
