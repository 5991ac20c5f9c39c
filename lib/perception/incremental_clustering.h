// SPDX-License-Identifier: Apache-2.0
// Euclidean clustering grown point by point, for the sweep clusterer (sweep_clusterer.h): each point
// joins its components as it arrives, so that a packet costs what its own points cost, not what is
// pending (issue 16: re-clustering every pending point on each packet cost a dense sensor's near car up
// to 9.8 ms a packet).
//
// The components are exactly cluster_grid's (euclidean_clustering.h) over the same points, whatever
// the order they arrive in: the same cells (diagonal just under the tolerance, so a cell's points are
// one component by construction; clustering_cell_size), the same float distance test, and union-find
// over the cells. An edge between two points is looked at when the later of them arrives: it is
// checked against the points of the 24 (planar; 124 spatial) cells within 2 cells of its own, unless
// that cell already is in its component. So every edge that could join two components is seen, and a
// point is touched O(1) times on arrival (a cell's bounding box skips cells beyond the tolerance;
// each cell keeps its neighbours' ids, so a point costs one hash lookup).
//
// Points leave only as whole components (take): what remains is then still exactly the components of
// the remaining points. Removing some points of a component (points gone stale) may split it: the
// caller takes everything (take_all) and adds back what it keeps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "lidar/point.h"
#include "perception/euclidean_clustering.h"
#include "perception/point_hash_grid.h"

namespace rsu::perception {

// A pending point with what the sweep clusterer keeps per point.
struct PendingPoint {
  lidar::LidarPoint point;
  double azimuth = 0.0;   // unwrapped beam azimuth (rad)
  double range = 0.0;     // planar, from the LiDAR (m)
  double close_at = 0.0;  // the sweep position past which this point can gain no neighbour
  std::uint64_t seq = 0;  // arrival order
};

// What the sweep clusterer needs of a component without visiting its points.
struct ComponentSummary {
  double min_azimuth = std::numeric_limits<double>::infinity();
  double max_azimuth = -std::numeric_limits<double>::infinity();
  double close_at = -std::numeric_limits<double>::infinity();  // largest of its points'
  double min_range = std::numeric_limits<double>::infinity();  // planar, from the LiDAR
  double max_range = -std::numeric_limits<double>::infinity();
  Eigen::AlignedBox2d box;  // planar bounding box of its points, map frame
  std::uint64_t first_seq = std::numeric_limits<std::uint64_t>::max();
  std::size_t size = 0;
};

class IncrementalClustering {
 public:
  // Uses config.tolerance_m and config.distance (the size limits are the caller's).
  explicit IncrementalClustering(const ClusteringConfig& config);

  // Whether add() accepts the point: cluster_grid's domain (finite, not beyond
  // clustering_max_abs_coordinate on an axis it uses).
  bool accepts(const lidar::LidarPoint& p) const;
  // Adds a point that accepts() (others are ignored).
  void add(const PendingPoint& p);

  std::size_t size() const { return points_; }  // points pending
  // The components, by id (valid until the next add, take or take_all), in no particular order.
  std::span<const std::uint32_t> components() const { return live_; }
  const ComponentSummary& summary(std::uint32_t component) const { return cells_[component].summary; }
  // Removes a component; its points in arrival order.
  std::vector<PendingPoint> take(std::uint32_t component);
  // A component's points in arrival order, left in place (what take would give now).
  std::vector<PendingPoint> copy(std::uint32_t component) const;
  // Removes everything; all points in arrival order.
  std::vector<PendingPoint> take_all();

 private:
  static constexpr std::int32_t kNone = -1;
  struct Cell {
    CellCoord coord;
    std::uint64_t key = 0;
    GridPoint lo;  // bounding box of its points
    GridPoint hi;
    std::vector<GridPoint> xyz;  // z = 0 when planar; parallel to points
    std::vector<PendingPoint> points;
    std::vector<std::int32_t> neighbours;  // cell id per offsets_ entry, kNone when empty
    std::uint32_t parent = 0;              // union-find over cells
    // Valid at a component's root cell:
    ComponentSummary summary;
    std::vector<std::uint32_t> member_cells;
    std::size_t live_index = 0;
  };

  GridPoint grid_point(const lidar::LidarPoint& p) const;
  CellCoord cell_of(const GridPoint& g) const;
  std::uint32_t cell_at(const CellCoord& c);  // existing or new
  std::uint32_t new_cell(const CellCoord& c, std::uint64_t key);
  void free_cell(std::uint32_t cell);
  std::uint32_t find(std::uint32_t cell);
  std::uint32_t unite(std::uint32_t root_a, std::uint32_t root_b);
  void unlist(std::uint32_t root);  // off the list of components
  bool any_within(const Cell& cell, const GridPoint& g) const;
  std::vector<PendingPoint> in_arrival_order(std::span<const std::uint32_t> members, std::size_t size) const;

  float tol2_;
  float prune2_;  // tol2_ with a margin against float rounding (bounding-box tests)
  float inv_cell_;
  float max_abs_;
  bool planar_;
  std::vector<CellCoord> offsets_;  // the cells within 2 per axis, lexicographic: -o is at size-1-k
  std::vector<Cell> cells_;
  std::vector<std::uint32_t> free_cells_;
  std::unordered_map<std::uint64_t, std::uint32_t> cell_by_key_;
  std::vector<std::uint32_t> live_;  // component roots
  std::size_t points_ = 0;
  // The previous point's cell: a firing's returns off one surface share a planar cell.
  std::uint64_t last_key_ = 0;
  std::int32_t last_cell_ = kNone;
};

}  // namespace rsu::perception
