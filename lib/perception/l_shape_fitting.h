// SPDX-License-Identifier: Apache-2.0
// L-shape rectangle fitting (Zhang et al. 2017), paper Sec. 3.1: the footprint points of one cluster
// -> the best-fitting rectangle under the chosen criterion and orientation search, plus, per edge, how
// many points support it and whether it faces the LiDAR (what the size correction needs to know).
//
// Bad input never throws: non-finite points are dropped and counted; too few points, or points on one
// line or one spot, give a RectangleFit with a status saying why and no geometry.
#pragma once

#include <span>

#include <Eigen/Core>

#include "perception/l_shape_criteria.h"
#include "perception/orientation_search.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

struct LShapeFitConfig {
  CriterionConfig criterion;       // closeness (Zhang, d0 = 0.01 m) by default
  OrientationSearchConfig search;  // coarse-to-fine by default; exhaustive 1 deg is the reference
  std::size_t min_points = 3;
  // Points spread less than this across their best line (or along it) are degenerate. 1 mm: real
  // returns of a vehicle face carry ~2 cm noise, so only synthetic or garbage input is this thin.
  double min_extent_m = 1e-3;
  double edge_support_m = 0.15;    // a point within this of an edge supports it (> 3 sigma of noise)
  double min_face_length_m = 0.3;  // shorter edges are not counted as seen faces
  std::size_t min_face_points = 3;
};

RectangleFit fit_rectangle(std::span<const Eigen::Vector2d> points, const Eigen::Vector2d& lidar_xy,
                           const LShapeFitConfig& config = {});

// Fills corners, center and edge information of `fit` from its yaw and the extents
// [c1_min, c1_max] x [c2_min, c2_max] along (yaw, yaw + pi/2) measured from `origin`. Shared with code
// that builds rectangles by hand (tests, known boxes).
void set_rectangle_geometry(RectangleFit& fit, const Eigen::Vector2d& origin, double c1_min, double c1_max,
                            double c2_min, double c2_max);
// Counts support and visibility of each edge of `fit` (geometry already set).
void set_edge_observations(RectangleFit& fit, std::span<const Eigen::Vector2d> points,
                           const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& config);

}  // namespace rsu::perception
