// SPDX-License-Identifier: Apache-2.0
// Background removal (c): a range-image model. Each (ring, azimuth bin) cell is one fixed beam
// direction of the spinning LiDAR, so the static scene gives it one background range. The model learns
// that range from several frames without vehicles and a point is foreground when it is closer than the
// background by more than a margin: one table lookup per point, no neighbour search.
//
// Learning (robust to noise and to sampling jitter):
//  - a cell's background is a near percentile (default 10 %, i.e. the minimum for fewer than 10 returns)
//    of its training ranges: a cell that straddles a pole and the wall behind it takes the pole, so
//    neither is later mistaken for foreground;
//  - the result is then the minimum over +-neighbour_bins azimuth bins, because the azimuth of a ring's
//    firings shifts from frame to frame (a rotation is not a whole number of firings) and beam-angle
//    noise moves returns across a bin edge;
//  - a cell that never returned ("sky", or beyond max range) has background +infinity: anything seen
//    there later is foreground.
// The margin grows with range: margin_m + margin_per_m * background_range, covering range noise
// (sigma 0.02 m) and the range change across a bin on surfaces seen obliquely.
//
// Ranges are horizontal distances from the LiDAR's map position: along a fixed beam they are the 3D
// range times a constant, so the comparison is the same and only the LiDAR's x, y are needed. Needs
// each point's ring and beam azimuth (LidarPoint::ring, ::azimuth_rad), which every source provides.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidar/point.h"
#include "perception/foreground.h"

namespace rsu::perception {

struct RangeImageBackgroundConfig {
  int azimuth_bins = 1800;       // 0.2 deg, the VLP azimuth step at 600 rpm (docs/design.md §2)
  int neighbour_bins = 1;        // background = min over bin +- this many
  double near_percentile = 0.1;  // of a cell's training ranges
  double margin_m = 0.3;
  double margin_per_m = 0.01;
  int max_rings = 256;  // rings >= this are invalid (a guard against garbage ring numbers)

  bool operator==(const RangeImageBackgroundConfig&) const = default;
};

class RangeImageBackground {
 public:
  RangeImageBackground(const Eigen::Vector2d& lidar_xy, const RangeImageBackgroundConfig& config = {});

  // Adds one frame recorded without vehicles (map frame) and recomputes the thresholds. Invalid points
  // (non-finite, ring >= max_rings) are ignored. Returns how many points were used.
  std::size_t add_training_frame(std::span<const lidar::LidarPoint> points);

  PointClass classify(const lidar::LidarPoint& p) const {
    if (!is_finite_point(p) || !std::isfinite(p.azimuth_rad) || p.ring >= max_rings_) {
      return PointClass::invalid;
    }
    if (p.ring >= rings_) {
      return PointClass::foreground;  // a ring that never returned in training is all sky
    }
    const float dx = p.x - lidar_x_;
    const float dy = p.y - lidar_y_;
    const float r2 = dx * dx + dy * dy;
    // Azimuth-major: a firing's rings lie side by side, so a column of points reads one or two cache
    // lines of the table instead of one per ring (the 128-ring table is 0.9 MB).
    const std::size_t cell = bin_of(p.azimuth_rad) * static_cast<std::size_t>(rings_) + p.ring;
    return r2 < threshold_sq_[cell] ? PointClass::foreground : PointClass::background;
  }

  ForegroundSelection select_foreground(std::span<const lidar::LidarPoint> points) const {
    return perception::select_foreground(points, [this](const lidar::LidarPoint& p) { return classify(p); });
  }

  int rings() const { return rings_; }
  int training_frames() const { return frames_; }
  // The learned background range of a cell (metres; +infinity for sky), for inspection and tests.
  float background_range(std::uint16_t ring, float azimuth_rad) const;

 private:
  std::size_t bin_of(float azimuth_rad) const {
    // azimuth_rad is in [0, 2 pi) by contract; anything else is wrapped into a valid bin.
    // Wrapped only when out of range: a 64-bit division for every point cost 6-15 % of the test's time.
    auto bin = static_cast<std::int64_t>(std::floor(azimuth_rad * bins_per_rad_));
    if (bin < 0 || bin >= bins_) {
      bin %= bins_;
      if (bin < 0) {
        bin += bins_;
      }
    }
    return static_cast<std::size_t>(bin);
  }
  // Ring-major (training samples, learned ranges: rings are added as they appear).
  std::size_t cell_index(std::uint16_t ring, float azimuth_rad) const {
    return static_cast<std::size_t>(ring) * static_cast<std::size_t>(bins_) + bin_of(azimuth_rad);
  }
  void recompute_thresholds();

  RangeImageBackgroundConfig config_;
  float lidar_x_;
  float lidar_y_;
  int bins_;
  float bins_per_rad_;
  int max_rings_;
  int rings_ = 0;
  int frames_ = 0;
  std::vector<std::vector<float>> samples_;  // per cell: training horizontal ranges
  std::vector<float> background_;            // per cell: learned background range (inf = sky)
  std::vector<float> threshold_sq_;          // per cell, azimuth-major: foreground iff r^2 < this
};

}  // namespace rsu::perception
