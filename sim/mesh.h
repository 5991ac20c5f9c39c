// SPDX-License-Identifier: Apache-2.0
// Triangle meshes for the simulated scene and the primitives the scene is built from.
//
// Winding convention: every triangle's vertices run counter-clockwise seen from outside, so the
// right-hand normal (v1 - v0) x (v2 - v0) points outward. All closed primitives here are watertight
// (every edge is shared by exactly two triangles, traversed in opposite directions), which keeps
// rays from leaking through seams.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rsu::sim {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;  // vertex indices, counter-clockwise seen from outside

  bool empty() const { return triangles.empty(); }
  // Adds `other` as a separate component (its indices are shifted; no vertices are merged).
  void append(const TriangleMesh& other);
  // Applies a rigid (or any affine) transform to every vertex in place.
  void transform(const Eigen::Affine3d& t);
};

TriangleMesh transformed(TriangleMesh mesh, const Eigen::Affine3d& t);

// Axis-aligned box between two opposite corners (min < max in each axis). 12 triangles.
TriangleMesh make_box(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner);

// Vertical cylinder about the z axis through (0, 0), from z0 to z1 (> z0), with both caps.
// `segments` (>= 3) vertices per ring, on the true cylinder (the polygonal mesh is inscribed).
TriangleMesh make_cylinder(double radius, double z0, double z1, int segments = 16);

// Ellipsoid centred at the origin with semi-axes `radii`, from a subdivided icosahedron
// (subdivisions = 0: 20 triangles; each level multiplies by 4). Vertices lie on the true surface.
TriangleMesh make_ellipsoid(const Eigen::Vector3d& radii, int subdivisions = 2);
inline TriangleMesh make_sphere(double radius, int subdivisions = 2) {
  return make_ellipsoid(Eigen::Vector3d::Constant(radius), subdivisions);
}

// A horizontal square of side 2 * half_extent centred at (0, 0, z), facing up (two triangles; an
// open surface, not a closed solid).
TriangleMesh make_ground_square(double half_extent, double z = 0.0);

// Straight prism: a convex polygon in the xy plane (counter-clockwise seen from above), extruded
// from z0 to z1 (> z0), capped. Used for the vehicle body's plan-view shapes.
TriangleMesh make_prism(const std::vector<Eigen::Vector2d>& convex_ccw, double z0, double z1);

// Loft between two convex rings (counter-clockwise seen from above, same vertex count, vertex i of
// `bottom` joined to vertex i of `top`), bottom ring at z0 and top ring at z1 (> z0), capped.
// Used for the glasshouse, whose roof outline is shorter than its base (sloped windscreen and rear).
TriangleMesh make_loft(const std::vector<Eigen::Vector2d>& bottom, double z0,
                       const std::vector<Eigen::Vector2d>& top, double z1);

// Rectangle with rounded corners centred at (cx, cy), half extents hx, hy, corner radius r
// (0 <= r <= min(hx, hy)), `arc_segments` (>= 1) per corner; counter-clockwise from the +x side.
// The extreme points x = cx +/- hx and y = cy +/- hy are vertices, so the bounding box is exact.
// The vertex count, 4 * (arc_segments + 1), does not depend on r, so two rings can be lofted.
std::vector<Eigen::Vector2d> rounded_rectangle(double cx, double cy, double hx, double hy, double r,
                                               int arc_segments);

// Part of a convex polygon with x in [x_min, x_max] (Sutherland-Hodgman against two half-planes).
std::vector<Eigen::Vector2d> clip_polygon_x(const std::vector<Eigen::Vector2d>& convex_ccw, double x_min,
                                            double x_max);

}  // namespace rsu::sim
