// SPDX-License-Identifier: Apache-2.0
// A uniform grid over points stored as an open-addressing hash map from cell to a contiguous run of
// points (points are sorted by cell). With the cell size at least the query radius, every point within
// r of q lies in the 3x3x3 (spatial) or 3x3 (planar) cells around q's cell, so "is any point within r"
// and "which points are within r" need only those cells: O(1) expected per query, and exact, because
// every candidate is checked by its true distance (the same answer as a k-d tree radius test).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace rsu::perception {

struct GridPoint {
  float x = 0.0F;
  float y = 0.0F;
  float z = 0.0F;
};

// planar: cells and distances use x and y only (z is ignored); spatial: x, y and z.
enum class GridDims { planar, spatial };

struct CellCoord {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;
};

// A cell's coordinates packed into one key, 21 bits per axis (the grid's domain, with a margin).
std::uint64_t cell_key(CellCoord c);

struct CellRun {
  std::uint32_t begin = 0;  // range in points()
  std::uint32_t end = 0;
};

class PointHashGrid {
 public:
  // Points that are non-finite or farther than max_abs_coordinate() from the origin on any axis are
  // left out of the grid and counted in skipped(). cell_size must be > 0 (else the grid is empty).
  PointHashGrid(std::span<const GridPoint> points, float cell_size, GridDims dims);

  // True when some grid point lies within `radius` of q (distance <= radius). radius is clamped to the
  // cell size, which is what guarantees exactness. False for a non-finite or out-of-range q.
  bool any_within(const GridPoint& q, float radius) const;

  // Whether q can be placed in the grid at all (finite and within max_abs_coordinate()).
  bool in_domain(const GridPoint& q) const;
  std::optional<CellCoord> cell_of(const GridPoint& q) const;
  std::optional<CellRun> find(CellCoord c) const;

  std::span<const GridPoint> points() const { return points_; }            // sorted by cell
  std::span<const std::uint32_t> source_index() const { return source_; }  // input index per point
  std::size_t cell_count() const { return cells_.size(); }
  CellCoord cell_coord(std::size_t cell) const { return cells_[cell]; }
  CellRun cell_run(std::size_t cell) const { return runs_[cell]; }
  std::size_t skipped() const { return skipped_; }
  float cell_size() const { return cell_size_; }
  GridDims dims() const { return dims_; }
  // Cell indices are packed into 21 bits each (with the +-1 neighbour margin), which bounds the domain.
  float max_abs_coordinate() const { return max_abs_; }

 private:
  std::optional<std::uint32_t> find_slot(std::uint64_t key) const;

  float cell_size_;
  float inv_cell_;
  float max_abs_;
  GridDims dims_;
  std::vector<GridPoint> points_;
  std::vector<std::uint32_t> source_;
  std::vector<CellCoord> cells_;
  std::vector<CellRun> runs_;
  std::vector<std::uint64_t> slot_key_;  // hash table: key per slot
  std::vector<std::int32_t> slot_cell_;  // hash table: cell index per slot, -1 = empty
  std::uint64_t slot_mask_ = 0;
  std::size_t skipped_ = 0;
};

}  // namespace rsu::perception
