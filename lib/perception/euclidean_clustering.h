// SPDX-License-Identifier: Apache-2.0
// Euclidean clustering (PCL's EuclideanClusterExtraction, as Autoware's euclidean_cluster runs it):
// points are connected when within `tolerance_m`, clusters are the connected components, and only
// components with min_points <= size <= max_points are kept. As in PCL, a component larger than
// max_points is dropped whole (not split), and counted.
//
// Distance: planar by default. Autoware's euclidean_cluster (parameter use_height: false, its default)
// sets z = 0 before clustering; we follow it. For a roadside LiDAR it also joins a vehicle's roof and
// body returns that a 3D tolerance would separate at long range, where rings are far apart vertically.
//
// Two implementations that give the same clusters:
//  - cluster_reference: breadth-first growth with brute-force neighbour search, O(n^2), obviously right;
//  - cluster_grid: hash grid with cells whose diagonal is the tolerance (so a cell is connected by
//    construction), union-find over the cells within reach, each pair of cells checked only until one
//    point pair within the tolerance connects them; O(n) expected.
// Both return clusters with ascending indices, ordered by their smallest index.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "lidar/point.h"

namespace rsu::perception {

enum class ClusterDistance { planar, spatial };

struct ClusteringConfig {
  double tolerance_m = 0.7;       // Autoware euclidean_cluster default
  std::size_t min_points = 10;    // Autoware default
  std::size_t max_points = 1000;  // Autoware default
  ClusterDistance distance = ClusterDistance::planar;
};

using Cluster = std::vector<std::uint32_t>;  // indices into the frame's points, ascending

struct Clustering {
  std::vector<Cluster> clusters;
  std::size_t dropped_small = 0;   // components with fewer than min_points
  std::size_t dropped_large = 0;   // components with more than max_points (dropped whole)
  std::size_t invalid_points = 0;  // non-finite or out-of-range points, left out
};

// `subset`: the indices of the points to cluster (e.g. the foreground); cluster indices refer to
// `points`. Indices outside `points` are counted as invalid.
Clustering cluster_reference(std::span<const lidar::LidarPoint> points, std::span<const std::uint32_t> subset,
                             const ClusteringConfig& config = {});
Clustering cluster_grid(std::span<const lidar::LidarPoint> points, std::span<const std::uint32_t> subset,
                        const ClusteringConfig& config = {});

// What cluster_grid's grid is built on, shared with the incremental clustering of the sweep
// (incremental_clustering.h) so that both connect exactly the same points:
// the largest |coordinate| clustered (points beyond are invalid), and the grid's cell size (diagonal
// just under the tolerance: a cell's points are connected by construction; points within the tolerance
// are at most 2 cells apart per axis). 0 for a tolerance that is not finite and positive.
float clustering_max_abs_coordinate(const ClusteringConfig& config);
float clustering_cell_size(const ClusteringConfig& config);

}  // namespace rsu::perception
