// SPDX-License-Identifier: Apache-2.0
#include "perception/range_image_background.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace rsu::perception {

RangeImageBackground::RangeImageBackground(const Eigen::Vector2d& lidar_xy,
                                           const RangeImageBackgroundConfig& config)
    : config_(config),
      lidar_x_(static_cast<float>(lidar_xy.x())),
      lidar_y_(static_cast<float>(lidar_xy.y())),
      bins_(std::max(1, config.azimuth_bins)),
      bins_per_rad_(static_cast<float>(static_cast<double>(bins_) / (2.0 * std::numbers::pi))),
      max_rings_(std::clamp(config.max_rings, 0, 65536)) {}

std::size_t RangeImageBackground::add_training_frame(std::span<const lidar::LidarPoint> points) {
  std::size_t used = 0;
  for (const auto& p : points) {
    if (!is_finite_point(p) || !std::isfinite(p.azimuth_rad) || p.ring >= max_rings_) {
      continue;
    }
    if (p.ring >= rings_) {
      rings_ = p.ring + 1;
      samples_.resize(static_cast<std::size_t>(rings_) * static_cast<std::size_t>(bins_));
    }
    const float dx = p.x - lidar_x_;
    const float dy = p.y - lidar_y_;
    samples_[cell_index(p.ring, p.azimuth_rad)].push_back(std::sqrt(dx * dx + dy * dy));
    ++used;
  }
  ++frames_;
  recompute_thresholds();
  return used;
}

void RangeImageBackground::recompute_thresholds() {
  constexpr float kSky = std::numeric_limits<float>::infinity();
  const std::size_t cells = samples_.size();
  std::vector<float> percentile(cells, kSky);
  const double q = std::clamp(config_.near_percentile, 0.0, 1.0);
  for (std::size_t c = 0; c < cells; ++c) {
    auto& s = samples_[c];
    if (s.empty()) {
      continue;
    }
    const auto k = static_cast<std::size_t>(q * static_cast<double>(s.size() - 1));
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(k), s.end());
    percentile[c] = s[k];
  }

  background_.assign(cells, kSky);
  threshold_sq_.assign(cells, kSky);
  const int reach = std::clamp(config_.neighbour_bins, 0, bins_ / 2);
  for (int ring = 0; ring < rings_; ++ring) {
    const std::size_t row = static_cast<std::size_t>(ring) * static_cast<std::size_t>(bins_);
    for (int bin = 0; bin < bins_; ++bin) {
      float nearest = kSky;
      for (int d = -reach; d <= reach; ++d) {
        const int b = ((bin + d) % bins_ + bins_) % bins_;  // azimuth wraps around
        nearest = std::min(nearest, percentile[row + static_cast<std::size_t>(b)]);
      }
      background_[row + static_cast<std::size_t>(bin)] = nearest;
      if (std::isfinite(nearest)) {
        const double bg = static_cast<double>(nearest);
        const double threshold = std::max(0.0, bg - config_.margin_m - config_.margin_per_m * bg);
        threshold_sq_[static_cast<std::size_t>(bin) * static_cast<std::size_t>(rings_) +
                      static_cast<std::size_t>(ring)] = static_cast<float>(threshold * threshold);
      }
    }
  }
}

float RangeImageBackground::background_range(std::uint16_t ring, float azimuth_rad) const {
  if (ring >= rings_ || !std::isfinite(azimuth_rad)) {
    return std::numeric_limits<float>::infinity();
  }
  return background_[cell_index(ring, azimuth_rad)];
}

}  // namespace rsu::perception
