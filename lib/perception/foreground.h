// SPDX-License-Identifier: Apache-2.0
// The common shape of every background-removal method: each point is classified on its own (O(1)),
// and a frame is reduced to the indices of its foreground points plus counted reasons for the rest.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "lidar/point.h"

namespace rsu::perception {

enum class PointClass : std::uint8_t {
  foreground,
  background,
  invalid,  // non-finite coordinates, or outside what the model can judge (e.g. an unknown ring)
};

struct ForegroundSelection {
  std::vector<std::uint32_t> indices;  // foreground points, indices into the input, ascending
  std::size_t background = 0;          // points classified as background
  std::size_t invalid = 0;             // points dropped as invalid (see PointClass::invalid)
};

inline bool is_finite_point(const lidar::LidarPoint& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// Runs `classify(point) -> PointClass` over a frame. Templated so that chained classifiers (ground
// prefilter, then a background model) inline into one pass over the points.
template <class Classifier>
ForegroundSelection select_foreground(std::span<const lidar::LidarPoint> points, Classifier&& classify) {
  ForegroundSelection out;
  out.indices.reserve(points.size() / 8);
  for (std::size_t i = 0; i < points.size(); ++i) {
    switch (classify(points[i])) {
      case PointClass::foreground:
        out.indices.push_back(static_cast<std::uint32_t>(i));
        break;
      case PointClass::background:
        ++out.background;
        break;
      case PointClass::invalid:
        ++out.invalid;
        break;
    }
  }
  return out;
}

}  // namespace rsu::perception
