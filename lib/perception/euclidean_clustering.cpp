// SPDX-License-Identifier: Apache-2.0
#include "perception/euclidean_clustering.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>

#include "perception/point_hash_grid.h"

namespace rsu::perception {
namespace {

// Both implementations cluster the same valid points: finite, and inside the grid's coordinate domain
// (+-2^20 cells of the smallest cell size cluster_grid uses; kilometres for any sensible tolerance).
struct ValidSubset {
  std::vector<std::uint32_t> index;  // into the frame
  std::vector<GridPoint> xyz;        // z = 0 in planar mode
  std::size_t invalid = 0;
};

ValidSubset valid_subset(std::span<const lidar::LidarPoint> points, std::span<const std::uint32_t> subset,
                         const ClusteringConfig& config) {
  const bool planar = config.distance == ClusterDistance::planar;
  const float tol = static_cast<float>(config.tolerance_m);
  const float max_abs = tol / std::sqrt(3.0F) * 0.99F * static_cast<float>((1 << 20) - 4);
  ValidSubset out;
  if (!(tol > 0.0F) || !std::isfinite(tol)) {  // no meaningful tolerance: nothing can be clustered
    out.invalid = subset.size();
    return out;
  }
  out.index.reserve(subset.size());
  out.xyz.reserve(subset.size());
  for (const std::uint32_t i : subset) {
    if (i >= points.size()) {
      ++out.invalid;
      continue;
    }
    const lidar::LidarPoint& p = points[i];
    const float z = planar ? 0.0F : p.z;
    const bool ok = std::abs(p.x) <= max_abs && std::abs(p.y) <= max_abs && std::abs(z) <= max_abs;
    if (!ok) {  // also rejects NaN
      ++out.invalid;
      continue;
    }
    out.index.push_back(i);
    out.xyz.push_back({p.x, p.y, z});
  }
  return out;
}

float squared_distance(const GridPoint& a, const GridPoint& b) {
  const float dx = a.x - b.x;
  const float dy = a.y - b.y;
  const float dz = a.z - b.z;
  return dx * dx + dy * dy + dz * dz;
}

// Size filter, index translation and canonical order shared by both implementations.
Clustering finish(const std::vector<std::vector<std::uint32_t>>& components, const ValidSubset& valid,
                  const ClusteringConfig& config) {
  Clustering out;
  out.invalid_points = valid.invalid;
  for (const auto& comp : components) {
    if (comp.size() < config.min_points) {
      ++out.dropped_small;
      continue;
    }
    if (comp.size() > config.max_points) {
      ++out.dropped_large;
      continue;
    }
    Cluster c;
    c.reserve(comp.size());
    for (const std::uint32_t k : comp) {
      c.push_back(valid.index[k]);
    }
    std::sort(c.begin(), c.end());
    out.clusters.push_back(std::move(c));
  }
  std::sort(out.clusters.begin(), out.clusters.end(),
            [](const Cluster& a, const Cluster& b) { return a.front() < b.front(); });
  return out;
}

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n), size_(n, 1) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t a) {
    while (parent_[a] != a) {
      parent_[a] = parent_[parent_[a]];  // path halving
      a = parent_[a];
    }
    return a;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    if (size_[a] < size_[b]) {
      std::swap(a, b);
    }
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint32_t> size_;
};

}  // namespace

Clustering cluster_reference(std::span<const lidar::LidarPoint> points, std::span<const std::uint32_t> subset,
                             const ClusteringConfig& config) {
  const ValidSubset valid = valid_subset(points, subset, config);
  const float tol2 = static_cast<float>(config.tolerance_m * config.tolerance_m);
  const std::size_t n = valid.xyz.size();
  std::vector<bool> visited(n, false);
  std::vector<std::vector<std::uint32_t>> components;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (visited[seed]) {
      continue;
    }
    std::vector<std::uint32_t> comp;
    std::deque<std::uint32_t> queue{static_cast<std::uint32_t>(seed)};
    visited[seed] = true;
    while (!queue.empty()) {
      const std::uint32_t a = queue.front();
      queue.pop_front();
      comp.push_back(a);
      for (std::size_t b = 0; b < n; ++b) {
        if (!visited[b] && squared_distance(valid.xyz[a], valid.xyz[b]) <= tol2) {
          visited[b] = true;
          queue.push_back(static_cast<std::uint32_t>(b));
        }
      }
    }
    components.push_back(std::move(comp));
  }
  return finish(components, valid, config);
}

Clustering cluster_grid(std::span<const lidar::LidarPoint> points, std::span<const std::uint32_t> subset,
                        const ClusteringConfig& config) {
  const ValidSubset valid = valid_subset(points, subset, config);
  const bool planar = config.distance == ClusterDistance::planar;
  const float tol = static_cast<float>(config.tolerance_m);
  const float tol2 = tol * tol;
  // Cell diagonal <= tolerance (cell = tol / sqrt(dims), a hair less against float rounding): all points
  // of a cell are within the tolerance of each other, so a cell is connected without distance checks,
  // and two cells need checking only until one pair connects them. Points within the tolerance are then
  // at most 2 cells apart per axis.
  const float cell = tol / std::sqrt(planar ? 2.0F : 3.0F) * 0.999F;
  const PointHashGrid grid(valid.xyz, cell, planar ? GridDims::planar : GridDims::spatial);
  const auto pts = grid.points();
  UnionFind sets(pts.size());

  // Each unordered pair of cells within reach is visited once: the offsets in [-2, 2]^d that are
  // lexicographically positive (12 planar, 62 spatial).
  std::vector<CellCoord> forward;
  const int z_reach = planar ? 0 : 2;
  for (int dz = -z_reach; dz <= z_reach; ++dz) {
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        if (dz > 0 || (dz == 0 && (dy > 0 || (dy == 0 && dx > 0)))) {
          forward.push_back({dx, dy, dz});
        }
      }
    }
  }
  for (std::size_t c = 0; c < grid.cell_count(); ++c) {
    const CellRun run = grid.cell_run(c);
    for (std::uint32_t a = run.begin + 1; a < run.end; ++a) {
      sets.unite(sets.find(run.begin), sets.find(a));
    }
  }
  for (std::size_t c = 0; c < grid.cell_count(); ++c) {
    const CellRun home = grid.cell_run(c);
    const CellCoord hc = grid.cell_coord(c);
    for (const CellCoord& o : forward) {
      const auto other = grid.find({hc.x + o.x, hc.y + o.y, hc.z + o.z});
      if (!other) {
        continue;
      }
      const std::uint32_t ra = sets.find(home.begin);
      const std::uint32_t rb = sets.find(other->begin);
      if (ra == rb) {
        continue;  // already one component
      }
      bool linked = false;
      for (std::uint32_t a = home.begin; a < home.end && !linked; ++a) {
        for (std::uint32_t b = other->begin; b < other->end; ++b) {
          if (squared_distance(pts[a], pts[b]) <= tol2) {
            sets.unite(ra, rb);
            linked = true;
            break;
          }
        }
      }
    }
  }

  // Components in grid order, then translated back to the valid-subset order the grid was built from.
  std::vector<std::int32_t> component_of_root(pts.size(), -1);
  std::vector<std::vector<std::uint32_t>> components;
  const auto source = grid.source_index();
  for (std::uint32_t k = 0; k < pts.size(); ++k) {
    const std::uint32_t root = sets.find(k);
    if (component_of_root[root] < 0) {
      component_of_root[root] = static_cast<std::int32_t>(components.size());
      components.emplace_back();
    }
    components[static_cast<std::size_t>(component_of_root[root])].push_back(source[k]);
  }
  return finish(components, valid, config);
}

}  // namespace rsu::perception
