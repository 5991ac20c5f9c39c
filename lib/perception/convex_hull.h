// SPDX-License-Identifier: Apache-2.0
// The vertices of a planar point set's convex hull. Any linear function of the points (a projection on a
// direction) takes its minimum and maximum at hull vertices, so the L-shape criteria
// (l_shape_criteria.h) find each candidate rectangle's edges from the hull's few dozen points instead of
// the cluster's thousands.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace rsu::perception {

// Indices of the hull's vertices, counter-clockwise (Andrew's monotone chain), collinear points on its
// edges left out. Fewer than three distinct points: the distinct ones. Points strictly inside the
// octagon of the extreme points in eight directions are dropped before the sort (Akl-Toussaint): they
// cannot be vertices, and in a vehicle's dense cluster they are most of it.
std::vector<std::size_t> convex_hull_vertices(std::span<const float> x, std::span<const float> y);

}  // namespace rsu::perception
