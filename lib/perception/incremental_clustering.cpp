// SPDX-License-Identifier: Apache-2.0
#include "perception/incremental_clustering.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace rsu::perception {
namespace {

constexpr std::size_t kKeptCapacity = 64;  // points a freed cell keeps room for

float box_gap(float lo, float hi, float v) {
  return std::max({0.0F, lo - v, v - hi});
}

void sort_by_arrival(std::vector<PendingPoint>& points) {
  std::sort(points.begin(), points.end(),
            [](const PendingPoint& a, const PendingPoint& b) { return a.seq < b.seq; });
}

}  // namespace

IncrementalClustering::IncrementalClustering(const ClusteringConfig& config)
    : max_abs_(clustering_max_abs_coordinate(config)), planar_(config.distance == ClusterDistance::planar) {
  const float tol = static_cast<float>(config.tolerance_m);
  tol2_ = tol * tol;  // as cluster_grid
  prune2_ = tol2_ * 1.0001F;
  const float cell = clustering_cell_size(config);
  inv_cell_ = max_abs_ > 0.0F ? 1.0F / cell : 0.0F;
  const int z_reach = planar_ ? 0 : 2;
  for (int dz = -z_reach; dz <= z_reach; ++dz) {
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        if (dx != 0 || dy != 0 || dz != 0)
          offsets_.push_back({dx, dy, dz});
      }
    }
  }
}

bool IncrementalClustering::accepts(const lidar::LidarPoint& p) const {
  const bool xy = std::abs(p.x) <= max_abs_ && std::abs(p.y) <= max_abs_;  // false for NaN
  return max_abs_ > 0.0F && xy && (planar_ || std::abs(p.z) <= max_abs_);
}

GridPoint IncrementalClustering::grid_point(const lidar::LidarPoint& p) const {
  return {p.x, p.y, planar_ ? 0.0F : p.z};
}

CellCoord IncrementalClustering::cell_of(const GridPoint& g) const {
  return {static_cast<std::int32_t>(std::floor(g.x * inv_cell_)),
          static_cast<std::int32_t>(std::floor(g.y * inv_cell_)),
          static_cast<std::int32_t>(std::floor(g.z * inv_cell_))};
}

std::uint32_t IncrementalClustering::cell_at(const CellCoord& c) {
  const std::uint64_t key = cell_key(c);
  if (last_cell_ != kNone && key == last_key_)
    return static_cast<std::uint32_t>(last_cell_);
  const auto it = cell_by_key_.find(key);
  const std::uint32_t cell = it != cell_by_key_.end() ? it->second : new_cell(c, key);
  last_key_ = key;
  last_cell_ = static_cast<std::int32_t>(cell);
  return cell;
}

std::uint32_t IncrementalClustering::new_cell(const CellCoord& c, std::uint64_t key) {
  std::uint32_t id = 0;
  if (!free_cells_.empty()) {
    id = free_cells_.back();
    free_cells_.pop_back();
  } else {
    id = static_cast<std::uint32_t>(cells_.size());
    cells_.emplace_back();
  }
  Cell& cell = cells_[id];
  cell.coord = c;
  cell.key = key;
  constexpr float kMax = std::numeric_limits<float>::max();
  cell.lo = {kMax, kMax, kMax};
  cell.hi = {-kMax, -kMax, -kMax};
  cell.xyz.clear();
  cell.points.clear();
  cell.parent = id;
  cell.summary = {};
  cell.member_cells.assign(1, id);
  cell.live_index = live_.size();
  live_.push_back(id);
  // Link the neighbours both ways, once per cell: a point then costs no lookup beyond its own cell's.
  cell.neighbours.assign(offsets_.size(), kNone);
  for (std::size_t k = 0; k < offsets_.size(); ++k) {
    const CellCoord& o = offsets_[k];
    const auto it = cell_by_key_.find(cell_key({c.x + o.x, c.y + o.y, c.z + o.z}));
    if (it == cell_by_key_.end())
      continue;
    cell.neighbours[k] = static_cast<std::int32_t>(it->second);
    cells_[it->second].neighbours[offsets_.size() - 1 - k] = static_cast<std::int32_t>(id);
  }
  cell_by_key_.emplace(key, id);
  return id;
}

void IncrementalClustering::free_cell(std::uint32_t id) {
  Cell& cell = cells_[id];
  for (std::size_t k = 0; k < offsets_.size(); ++k) {
    if (cell.neighbours[k] != kNone)
      cells_[static_cast<std::size_t>(cell.neighbours[k])].neighbours[offsets_.size() - 1 - k] = kNone;
  }
  cell_by_key_.erase(cell.key);
  if (last_cell_ == static_cast<std::int32_t>(id))
    last_cell_ = kNone;
  points_ -= cell.points.size();
  // A freed cell is reused for any other: one that held a dense sensor's near car (hundreds of points)
  // gives its memory back, else every slot would grow, one after the other, to the densest cell seen
  // (rsud's RSS grew 60 MB/min in rsud_load.py --ouster).
  if (cell.points.capacity() > kKeptCapacity) {
    cell.points = {};
    cell.xyz = {};
  }
  free_cells_.push_back(id);
}

std::uint32_t IncrementalClustering::find(std::uint32_t cell) {
  while (cells_[cell].parent != cell) {
    cells_[cell].parent = cells_[cells_[cell].parent].parent;  // path halving
    cell = cells_[cell].parent;
  }
  return cell;
}

std::uint32_t IncrementalClustering::unite(std::uint32_t a, std::uint32_t b) {
  if (cells_[a].member_cells.size() < cells_[b].member_cells.size())
    std::swap(a, b);
  Cell& root = cells_[a];
  Cell& gone = cells_[b];
  gone.parent = a;
  ComponentSummary& s = root.summary;
  const ComponentSummary& t = gone.summary;
  s.min_azimuth = std::min(s.min_azimuth, t.min_azimuth);
  s.max_azimuth = std::max(s.max_azimuth, t.max_azimuth);
  s.close_at = std::max(s.close_at, t.close_at);
  s.min_range = std::min(s.min_range, t.min_range);
  s.max_range = std::max(s.max_range, t.max_range);
  s.box.extend(t.box);
  s.first_seq = std::min(s.first_seq, t.first_seq);
  s.size += t.size;
  root.member_cells.insert(root.member_cells.end(), gone.member_cells.begin(), gone.member_cells.end());
  std::vector<std::uint32_t>().swap(gone.member_cells);  // its memory too (see free_cell)
  unlist(b);
  return a;
}

void IncrementalClustering::unlist(std::uint32_t root) {
  const std::uint32_t moved = live_.back();  // takes its place
  live_[cells_[root].live_index] = moved;
  cells_[moved].live_index = cells_[root].live_index;
  live_.pop_back();
}

bool IncrementalClustering::any_within(const Cell& cell, const GridPoint& g) const {
  const float dx = box_gap(cell.lo.x, cell.hi.x, g.x);
  const float dy = box_gap(cell.lo.y, cell.hi.y, g.y);
  const float dz = box_gap(cell.lo.z, cell.hi.z, g.z);
  if (dx * dx + dy * dy + dz * dz > prune2_)
    return false;
  for (const GridPoint& q : cell.xyz) {
    const float ex = q.x - g.x;
    const float ey = q.y - g.y;
    const float ez = q.z - g.z;
    if (ex * ex + ey * ey + ez * ez <= tol2_)
      return true;
  }
  return false;
}

void IncrementalClustering::add(const PendingPoint& p) {
  if (!accepts(p.point))
    return;
  const GridPoint g = grid_point(p.point);
  const std::uint32_t id = cell_at(cell_of(g));
  {
    Cell& cell = cells_[id];
    cell.lo = {std::min(cell.lo.x, g.x), std::min(cell.lo.y, g.y), std::min(cell.lo.z, g.z)};
    cell.hi = {std::max(cell.hi.x, g.x), std::max(cell.hi.y, g.y), std::max(cell.hi.z, g.z)};
    cell.xyz.push_back(g);
    cell.points.push_back(p);
  }
  ++points_;
  std::uint32_t root = find(id);
  ComponentSummary& s = cells_[root].summary;
  s.min_azimuth = std::min(s.min_azimuth, p.azimuth);
  s.max_azimuth = std::max(s.max_azimuth, p.azimuth);
  s.close_at = std::max(s.close_at, p.close_at);
  s.min_range = std::min(s.min_range, p.range);
  s.max_range = std::max(s.max_range, p.range);
  s.box.extend(Eigen::Vector2d(p.point.x, p.point.y));
  s.first_seq = std::min(s.first_seq, p.seq);
  ++s.size;
  // The point's edges to earlier points: only those into another component can change anything.
  for (std::size_t k = 0; k < offsets_.size(); ++k) {
    const std::int32_t n = cells_[id].neighbours[k];
    if (n == kNone)
      continue;
    const std::uint32_t other = find(static_cast<std::uint32_t>(n));
    if (other != root && any_within(cells_[static_cast<std::size_t>(n)], g))
      root = unite(root, other);
  }
}

std::vector<PendingPoint> IncrementalClustering::in_arrival_order(std::span<const std::uint32_t> members,
                                                                  std::size_t size) const {
  // Each cell's points are in arrival order already; the cells' are interleaved. Arrival numbers are
  // unique and a component's span few others (what arrived among its points: mostly its own, near a
  // dense sensor's car 10-20 k of them), so each point goes to the slot of its number and the slots are
  // read in order; where the span is wide (components far apart in arrival joined late), small keys are
  // sorted instead. Either way the order is the arrival order.
  std::uint64_t first = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t last = 0;
  for (const std::uint32_t c : members) {
    for (const PendingPoint& p : cells_[c].points) {
      first = std::min(first, p.seq);
      last = std::max(last, p.seq);
    }
  }
  std::vector<PendingPoint> out;
  out.reserve(size);
  if (size == 0 || first > last)
    return out;
  if (last - first < 4 * static_cast<std::uint64_t>(size) + 64) {
    std::vector<const PendingPoint*> slots(last - first + 1, nullptr);
    for (const std::uint32_t c : members) {
      for (const PendingPoint& p : cells_[c].points)
        slots[p.seq - first] = &p;
    }
    for (const PendingPoint* p : slots) {
      if (p != nullptr)
        out.push_back(*p);
    }
    return out;
  }
  std::vector<std::pair<std::uint64_t, const PendingPoint*>> order;
  order.reserve(size);
  for (const std::uint32_t c : members) {
    for (const PendingPoint& p : cells_[c].points)
      order.emplace_back(p.seq, &p);
  }
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [seq, p] : order)
    out.push_back(*p);
  return out;
}

std::vector<PendingPoint> IncrementalClustering::take(std::uint32_t component) {
  Cell& root = cells_[component];
  const std::vector<std::uint32_t> members = std::move(root.member_cells);
  root.member_cells.clear();
  unlist(component);
  std::vector<PendingPoint> out = in_arrival_order(members, root.summary.size);
  for (const std::uint32_t c : members)
    free_cell(c);
  return out;
}

std::vector<PendingPoint> IncrementalClustering::copy(std::uint32_t component) const {
  const Cell& root = cells_[component];
  return in_arrival_order(root.member_cells, root.summary.size);
}

std::vector<PendingPoint> IncrementalClustering::take_all() {
  std::vector<PendingPoint> out;
  out.reserve(points_);
  while (!live_.empty()) {
    std::vector<PendingPoint> part = take(live_.back());
    out.insert(out.end(), part.begin(), part.end());
  }
  sort_by_arrival(out);
  return out;
}

}  // namespace rsu::perception
