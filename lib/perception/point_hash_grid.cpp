// SPDX-License-Identifier: Apache-2.0
#include "perception/point_hash_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

#include "common/random.h"

namespace rsu::perception {
namespace {

constexpr std::int32_t kCoordBias = 1 << 20;  // 21 bits per axis: [-2^20, 2^20)
constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << 21) - 1;

float squared_distance(const GridPoint& a, const GridPoint& b, GridDims dims) {
  const float dx = a.x - b.x;
  const float dy = a.y - b.y;
  const float dz = dims == GridDims::spatial ? a.z - b.z : 0.0F;
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

std::uint64_t cell_key(CellCoord c) {
  const auto ux = static_cast<std::uint64_t>(c.x + kCoordBias) & kAxisMask;
  const auto uy = static_cast<std::uint64_t>(c.y + kCoordBias) & kAxisMask;
  const auto uz = static_cast<std::uint64_t>(c.z + kCoordBias) & kAxisMask;
  return ux | (uy << 21) | (uz << 42);
}

PointHashGrid::PointHashGrid(std::span<const GridPoint> points, float cell_size, GridDims dims)
    : cell_size_(cell_size > 0.0F && std::isfinite(cell_size) ? cell_size : 0.0F),
      inv_cell_(cell_size_ > 0.0F ? 1.0F / cell_size_ : 0.0F),
      // Leave a few cells of margin so that neighbour cells (+-1) of any accepted point still pack.
      max_abs_(cell_size_ * static_cast<float>(kCoordBias - 4)),
      dims_(dims) {
  if (cell_size_ <= 0.0F) {
    skipped_ = points.size();
    return;
  }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto cell = cell_of(points[i]);
    if (!cell) {
      ++skipped_;
      continue;
    }
    keyed.emplace_back(cell_key(*cell), static_cast<std::uint32_t>(i));
  }
  std::sort(keyed.begin(), keyed.end());

  points_.reserve(keyed.size());
  source_.reserve(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    const std::uint32_t i = keyed[k].second;
    if (k == 0 || keyed[k].first != keyed[k - 1].first) {
      cells_.push_back(*cell_of(points[i]));
      runs_.push_back({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k)});
    }
    ++runs_.back().end;
    points_.push_back(points[i]);
    source_.push_back(i);
  }

  // Load factor <= 1/2 keeps linear probing short.
  const std::size_t capacity = std::bit_ceil(std::max<std::size_t>(16, 2 * cells_.size()));
  slot_mask_ = capacity - 1;
  slot_key_.assign(capacity, 0);
  slot_cell_.assign(capacity, -1);
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    const std::uint64_t key = cell_key(cells_[c]);
    std::uint64_t slot = mix64(key) & slot_mask_;
    while (slot_cell_[slot] >= 0) {
      slot = (slot + 1) & slot_mask_;
    }
    slot_key_[slot] = key;
    slot_cell_[slot] = static_cast<std::int32_t>(c);
  }
}

bool PointHashGrid::in_domain(const GridPoint& q) const {
  const bool xy_ok = std::abs(q.x) <= max_abs_ && std::abs(q.y) <= max_abs_;  // false for NaN
  const bool z_ok = dims_ == GridDims::planar || std::abs(q.z) <= max_abs_;
  return cell_size_ > 0.0F && xy_ok && z_ok;
}

std::optional<CellCoord> PointHashGrid::cell_of(const GridPoint& q) const {
  if (!in_domain(q)) {
    return std::nullopt;
  }
  CellCoord c;
  c.x = static_cast<std::int32_t>(std::floor(q.x * inv_cell_));
  c.y = static_cast<std::int32_t>(std::floor(q.y * inv_cell_));
  c.z = dims_ == GridDims::spatial ? static_cast<std::int32_t>(std::floor(q.z * inv_cell_)) : 0;
  return c;
}

std::optional<std::uint32_t> PointHashGrid::find_slot(std::uint64_t key) const {
  if (slot_cell_.empty()) {
    return std::nullopt;
  }
  std::uint64_t slot = mix64(key) & slot_mask_;
  while (slot_cell_[slot] >= 0) {
    if (slot_key_[slot] == key) {
      return static_cast<std::uint32_t>(slot_cell_[slot]);
    }
    slot = (slot + 1) & slot_mask_;
  }
  return std::nullopt;
}

std::optional<CellRun> PointHashGrid::find(CellCoord c) const {
  const auto cell = find_slot(cell_key(c));
  if (!cell) {
    return std::nullopt;
  }
  return runs_[*cell];
}

bool PointHashGrid::any_within(const GridPoint& q, float radius) const {
  const auto home = cell_of(q);
  if (!home || !(radius >= 0.0F)) {
    return false;
  }
  const float r = std::min(radius, cell_size_);
  const float r2 = r * r;
  auto run_has_hit = [&](const CellRun& run) {
    for (std::uint32_t k = run.begin; k < run.end; ++k) {
      if (squared_distance(points_[k], q, dims_) <= r2) {
        return true;
      }
    }
    return false;
  };
  // The home cell first: a background point almost always finds its match there, ending the query.
  if (const auto run = find(*home); run && run_has_hit(*run)) {
    return true;
  }
  // Gap from q to the low and high face of its cell along each axis; a neighbour cell whose nearest
  // point is farther than r cannot hold a hit and is not looked up.
  const float fx = q.x * inv_cell_ - static_cast<float>(home->x);
  const float fy = q.y * inv_cell_ - static_cast<float>(home->y);
  const float fz = q.z * inv_cell_ - static_cast<float>(home->z);
  const float gap_low[3] = {fx * cell_size_, fy * cell_size_, fz * cell_size_};
  const float gap_high[3] = {(1.0F - fx) * cell_size_, (1.0F - fy) * cell_size_, (1.0F - fz) * cell_size_};
  auto axis_gap2 = [&](int axis, int d) {
    const float g = d < 0 ? gap_low[axis] : (d > 0 ? gap_high[axis] : 0.0F);
    return g * g;
  };
  const int z_span = dims_ == GridDims::spatial ? 1 : 0;
  for (int dz = -z_span; dz <= z_span; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) {
          continue;
        }
        const float gap2 = axis_gap2(0, dx) + axis_gap2(1, dy) + (z_span != 0 ? axis_gap2(2, dz) : 0.0F);
        if (gap2 > r2 * 1.0001F) {  // slack: fx, fy, fz carry float rounding
          continue;
        }
        const auto run = find({home->x + dx, home->y + dy, home->z + dz});
        if (run && run_has_hit(*run)) {
          return true;
        }
      }
    }
  }
  return false;
}

}  // namespace rsu::perception
