// SPDX-License-Identifier: Apache-2.0
// Least-squares refinement of a fitted rectangle's orientation on the faces the LiDAR saw.
//
// The search criteria of Zhang et al. score angles by how close points come to the bounding edges; with
// d0 = 0.01 m and 2 cm range noise the optimum follows the few points that happen to line up, so on a
// short face (a car's 1.9 m front seen alone) the yaw can be off by several degrees, which the size
// correction turns into centre error (yaw error x half the length). Fitting straight lines to the seen
// faces' points by least squares uses every point: with faces A (running along e1) and B (along e2)
// and unit normal n of A, minimise
//   sum_A (n . (p - mean_A))^2 + sum_B (n_perp . (p - mean_B))^2 = n^T (S_A - S_B) n + trace(S_B),
// S the faces' scatter matrices, so n is the eigenvector of S_A - S_B with the smaller eigenvalue
// (one face: S_B = 0, the total-least-squares line). Points near a face's ends are left out: real
// vehicles round their corners (docs/design.md §2 vehicle: 0.35 m radius in the simulator).
#pragma once

#include <span>

#include <Eigen/Core>

#include "perception/l_shape_fitting.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

struct FaceRefinementConfig {
  double corner_exclusion_m = 0.3;  // points closer than this to a face's ends are not used
  double max_change_rad = 0.1745;   // refinements larger than 10 deg are rejected (the fit is kept)
  std::size_t min_face_points = 3;
  // refit_unsettled_rad: refits after the first, at most.
  std::size_t settle_passes = 5;
};

// The fit with its orientation re-estimated from the seen faces and its extents and edges recomputed
// from `points` (the cluster the fit came from). Returns `fit` unchanged if it is not ok, no face has
// enough points, or the change is implausibly large.
RectangleFit refine_on_faces(const RectangleFit& fit, std::span<const Eigen::Vector2d> points,
                             const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& fit_config = {},
                             const FaceRefinementConfig& config = {});

// How far from `refined` (a refit: refine_on_faces) its direction moves when it is refit again, pass after
// pass on the last refit's faces (at most config.settle_passes, until a turn is under a thousandth of a
// radian): the largest departure, mod pi. Each refit takes the faces' points within the support band of the
// last rectangle's edges, so one refit of a fit several degrees off stays near it; its direction is then
// not what the faces' points settle on (small cars 33-38 m from a mast 4-8 m up, their fits 5-7 deg off:
// one refit left them 5.4-7.1 deg off stating 1.5-2.2 deg; refit again, 0.4-4.2 deg off, one in a cycle).
double refit_unsettled_rad(const RectangleFit& refined, std::span<const Eigen::Vector2d> points,
                           const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& fit_config = {},
                           const FaceRefinementConfig& config = {});

}  // namespace rsu::perception
