// SPDX-License-Identifier: Apache-2.0
#include "perception/euclidean_clustering.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
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
  const float max_abs = clustering_max_abs_coordinate(config);
  ValidSubset out;
  if (!(max_abs > 0.0F)) {  // no meaningful tolerance: nothing can be clustered
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

// The bounding box of a cell's points, and squared gaps to another box or a point (0 when they overlap).
struct CellBox {
  GridPoint lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
               std::numeric_limits<float>::max()};
  GridPoint hi{std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(),
               std::numeric_limits<float>::lowest()};
  void add(const GridPoint& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  static float gap(float lo_a, float hi_a, float lo_b, float hi_b) {
    return std::max({0.0F, lo_a - hi_b, lo_b - hi_a});
  }
  float gap2(const CellBox& o) const {
    const float dx = gap(lo.x, hi.x, o.lo.x, o.hi.x);
    const float dy = gap(lo.y, hi.y, o.lo.y, o.hi.y);
    const float dz = gap(lo.z, hi.z, o.lo.z, o.hi.z);
    return dx * dx + dy * dy + dz * dz;
  }
  float gap2(const GridPoint& p) const {
    const float dx = gap(lo.x, hi.x, p.x, p.x);
    const float dy = gap(lo.y, hi.y, p.y, p.y);
    const float dz = gap(lo.z, hi.z, p.z, p.z);
    return dx * dx + dy * dy + dz * dz;
  }
};

// Each unordered pair of cells within reach is visited once: the offsets in [-2, 2]^d that are
// lexicographically positive (12 planar, 62 spatial).
std::vector<CellCoord> forward_offsets(bool planar) {
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
  return forward;
}

// Whether a point of `home` lies within the tolerance of a point of `other`; home's points farther than
// it from other's box are not compared.
bool any_pair_within(std::span<const GridPoint> pts, const CellRun& home, const CellRun& other,
                     const CellBox& other_box, float tol2, float prune2) {
  for (std::uint32_t a = home.begin; a < home.end; ++a) {
    if (other_box.gap2(pts[a]) > prune2) {
      continue;
    }
    for (std::uint32_t b = other.begin; b < other.end; ++b) {
      if (squared_distance(pts[a], pts[b]) <= tol2) {
        return true;
      }
    }
  }
  return false;
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

float clustering_max_abs_coordinate(const ClusteringConfig& config) {
  const float tol = static_cast<float>(config.tolerance_m);
  if (!(tol > 0.0F) || !std::isfinite(tol))
    return 0.0F;
  return tol / std::sqrt(3.0F) * 0.99F * static_cast<float>((1 << 20) - 4);
}

float clustering_cell_size(const ClusteringConfig& config) {
  const float tol = static_cast<float>(config.tolerance_m);
  const bool planar = config.distance == ClusterDistance::planar;
  return tol / std::sqrt(planar ? 2.0F : 3.0F) * 0.999F;
}

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
  const float cell = clustering_cell_size(config);
  const PointHashGrid grid(valid.xyz, cell, planar ? GridDims::planar : GridDims::spatial);
  const auto pts = grid.points();
  UnionFind sets(pts.size());

  const std::vector<CellCoord> forward = forward_offsets(planar);
  // Each cell's bounding box: a pair of cells whose boxes lie farther apart than the tolerance cannot
  // connect, and of the two, only points within the tolerance of the other's box can. Without it two
  // dense cells two apart diagonally (whose nearest corners are 0.999 x the tolerance apart) were checked
  // point pair by point pair: a dense sensor's car 10 m away put hundreds of points in a cell, and that
  // product led the 128-ring pipeline's profile (issue 16). A margin against float rounding keeps the
  // pruning exact.
  std::vector<CellBox> boxes(grid.cell_count());
  std::vector<std::uint32_t> box_of_run_start(pts.size());  // cell of a run's first point
  for (std::size_t c = 0; c < grid.cell_count(); ++c) {
    const CellRun run = grid.cell_run(c);
    box_of_run_start[run.begin] = static_cast<std::uint32_t>(c);
    for (std::uint32_t a = run.begin; a < run.end; ++a) {
      boxes[c].add(pts[a]);
    }
    for (std::uint32_t a = run.begin + 1; a < run.end; ++a) {
      sets.unite(sets.find(run.begin), sets.find(a));
    }
  }
  const float prune2 = tol2 * 1.0001F;
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
      const CellBox& other_box = boxes[box_of_run_start[other->begin]];
      if (boxes[c].gap2(other_box) > prune2) {
        continue;
      }
      if (any_pair_within(pts, home, *other, other_box, tol2, prune2)) {
        sets.unite(ra, rb);
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
