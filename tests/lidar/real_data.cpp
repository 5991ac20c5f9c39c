// SPDX-License-Identifier: Apache-2.0
#include "real_data.h"

#include <cmath>
#include <unordered_map>

namespace rsu::lidar::test {
namespace {

struct Cell {
  std::int64_t x, y, z;
  bool operator==(const Cell&) const = default;
};
struct CellHash {
  std::size_t operator()(const Cell& c) const {
    return static_cast<std::size_t>(c.x * 73856093 ^ c.y * 19349663 ^ c.z * 83492791);
  }
};

Cell cell_of(const LidarPoint& p, double size) {
  return {static_cast<std::int64_t>(std::floor(static_cast<double>(p.x) / size)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.y) / size)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.z) / size))};
}

double distance_sq(const LidarPoint& a, const LidarPoint& b) {
  const double dx = static_cast<double>(a.x) - static_cast<double>(b.x);
  const double dy = static_cast<double>(a.y) - static_cast<double>(b.y);
  const double dz = static_cast<double>(a.z) - static_cast<double>(b.z);
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

double share_matched(std::span<const LidarPoint> reference, std::span<const LidarPoint> ours, double radius) {
  if (reference.empty())
    return 0.0;
  std::unordered_map<Cell, std::vector<std::size_t>, CellHash> grid;
  for (std::size_t i = 0; i < ours.size(); ++i)
    grid[cell_of(ours[i], radius)].push_back(i);
  std::size_t matched = 0;
  for (const LidarPoint& r : reference) {
    const Cell c = cell_of(r, radius);
    bool found = false;
    for (std::int64_t dx = -1; dx <= 1 && !found; ++dx) {
      for (std::int64_t dy = -1; dy <= 1 && !found; ++dy) {
        for (std::int64_t dz = -1; dz <= 1 && !found; ++dz) {
          const auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end())
            continue;
          for (const std::size_t i : it->second) {
            if (distance_sq(r, ours[i]) <= radius * radius) {
              found = true;
              break;
            }
          }
        }
      }
    }
    matched += found ? 1 : 0;
  }
  return static_cast<double>(matched) / static_cast<double>(reference.size());
}

}  // namespace rsu::lidar::test
