// SPDX-License-Identifier: Apache-2.0
// The result of L-shape fitting: a 2D rectangle in the map frame plus what the LiDAR saw of it.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

#include <Eigen/Core>

namespace rsu::perception {

enum class FitStatus {
  ok,
  too_few_points,     // fewer than LShapeFitConfig::min_points finite points
  non_finite_points,  // too few points once the non-finite ones were dropped (some were)
  degenerate,         // all points (nearly) on one line or one spot: no rectangle is defined
};

std::string_view to_string(FitStatus status);

// One side of the rectangle. Edge k runs from corners[k] to corners[(k + 1) % 4].
struct RectangleEdge {
  std::size_t support_points = 0;  // cluster points within LShapeFitConfig::edge_support_m of the edge
  bool faces_lidar = false;        // the LiDAR is on the outer side of the edge's line
  // Faces the LiDAR, long enough to be a real face (>= min_face_length_m) and has >= min_face_points
  // support points. A thin one-face fit has short end edges that are not "seen" though they have support.
  bool seen = false;
};

struct RectangleFit {
  FitStatus status = FitStatus::too_few_points;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double yaw = 0.0;      // direction of the first edge (corners[0] -> corners[1]), [0, pi/2)
  double length0 = 0.0;  // first edge (along yaw)
  double length1 = 0.0;  // second edge (along yaw + pi/2)
  // Counter-clockwise, starting at the corner with the smallest coordinates along (yaw, yaw + pi/2).
  std::array<Eigen::Vector2d, 4> corners{};
  std::array<RectangleEdge, 4> edges{};
  double criterion_value = 0.0;
  std::size_t points_used = 0;
  std::size_t non_finite_dropped = 0;

  bool ok() const { return status == FitStatus::ok; }
  // Unit vectors along the first and second edge.
  Eigen::Vector2d axis0() const;
  Eigen::Vector2d axis1() const;
};

}  // namespace rsu::perception
