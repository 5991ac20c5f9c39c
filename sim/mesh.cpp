// SPDX-License-Identifier: Apache-2.0
#include "sim/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/angles.h"

namespace rsu::sim {
namespace {

void require(bool ok, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("mesh: ") + what);
  }
}

bool finite_polygon(const std::vector<Eigen::Vector2d>& polygon) {
  for (const auto& p : polygon) {
    if (!p.allFinite()) {
      return false;
    }
  }
  return true;
}

int add_vertex(TriangleMesh& mesh, double x, double y, double z) {
  mesh.vertices.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  return static_cast<int>(mesh.vertices.size()) - 1;
}

}  // namespace

void TriangleMesh::append(const TriangleMesh& other) {
  const int offset = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const auto& t : other.triangles) {
    triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
}

void TriangleMesh::transform(const Eigen::Affine3d& t) {
  for (auto& v : vertices) {
    v = (t * v.cast<double>()).cast<float>();
  }
}

TriangleMesh transformed(TriangleMesh mesh, const Eigen::Affine3d& t) {
  mesh.transform(t);
  return mesh;
}

TriangleMesh make_loft(const std::vector<Eigen::Vector2d>& bottom, double z0,
                       const std::vector<Eigen::Vector2d>& top, double z1) {
  require(bottom.size() >= 3 && bottom.size() == top.size(), "loft rings need >= 3 and equal vertex counts");
  require(finite_polygon(bottom) && finite_polygon(top) && std::isfinite(z0) && std::isfinite(z1) && z1 > z0,
          "loft needs finite rings and z1 > z0");
  const int n = static_cast<int>(bottom.size());
  TriangleMesh mesh;
  mesh.vertices.reserve(2 * bottom.size());
  for (const auto& p : bottom) {
    add_vertex(mesh, p.x(), p.y(), z0);
  }
  for (const auto& p : top) {
    add_vertex(mesh, p.x(), p.y(), z1);
  }
  mesh.triangles.reserve(4 * bottom.size());
  for (int i = 0; i < n; ++i) {
    // Side quad b_i, b_i+1, t_i+1, t_i: counter-clockwise seen from outside because the rings are
    // counter-clockwise seen from above.
    const int j = (i + 1) % n;
    mesh.triangles.emplace_back(i, j, n + j);
    mesh.triangles.emplace_back(i, n + j, n + i);
  }
  // Caps as fans from vertex 0 (valid because the rings are convex): bottom faces down, top up.
  for (int i = 1; i + 1 < n; ++i) {
    mesh.triangles.emplace_back(0, i + 1, i);
    mesh.triangles.emplace_back(n, n + i, n + i + 1);
  }
  return mesh;
}

TriangleMesh make_prism(const std::vector<Eigen::Vector2d>& convex_ccw, double z0, double z1) {
  return make_loft(convex_ccw, z0, convex_ccw, z1);
}

TriangleMesh make_box(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner) {
  require(min_corner.allFinite() && max_corner.allFinite() && (max_corner.array() > min_corner.array()).all(),
          "box needs finite corners with min < max");
  const std::vector<Eigen::Vector2d> rect = {{max_corner.x(), min_corner.y()},
                                             {max_corner.x(), max_corner.y()},
                                             {min_corner.x(), max_corner.y()},
                                             {min_corner.x(), min_corner.y()}};
  return make_prism(rect, min_corner.z(), max_corner.z());
}

TriangleMesh make_cylinder(double radius, double z0, double z1, int segments) {
  require(std::isfinite(radius) && radius > 0.0 && segments >= 3,
          "cylinder needs radius > 0 and >= 3 segments");
  std::vector<Eigen::Vector2d> ring;
  ring.reserve(static_cast<std::size_t>(segments));
  for (int i = 0; i < segments; ++i) {
    const double a = 2.0 * kPi * i / segments;
    ring.emplace_back(radius * std::cos(a), radius * std::sin(a));
  }
  return make_prism(ring, z0, z1);
}

TriangleMesh make_ellipsoid(const Eigen::Vector3d& radii, int subdivisions) {
  require(radii.allFinite() && (radii.array() > 0.0).all(), "ellipsoid needs finite positive radii");
  require(subdivisions >= 0 && subdivisions <= 7, "ellipsoid subdivisions must be in [0, 7]");
  // Icosahedron: the 12 vertices are the cyclic permutations of (0, +-1, +-phi).
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> unit = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                       {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                       {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (auto& v : unit) {
    v.normalize();
  }
  std::vector<Eigen::Vector3i> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    // Each edge's midpoint is created once and shared by both neighbouring faces (watertight).
    std::map<std::pair<int, int>, int> midpoint_of_edge;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoint_of_edge.find(key);
      if (it != midpoint_of_edge.end()) {
        return it->second;
      }
      unit.push_back((unit[static_cast<std::size_t>(a)] + unit[static_cast<std::size_t>(b)]).normalized());
      const int index = static_cast<int>(unit.size()) - 1;
      midpoint_of_edge.emplace(key, index);
      return index;
    };
    std::vector<Eigen::Vector3i> finer;
    finer.reserve(4 * faces.size());
    for (const auto& f : faces) {
      const int ab = midpoint(f[0], f[1]);
      const int bc = midpoint(f[1], f[2]);
      const int ca = midpoint(f[2], f[0]);
      finer.emplace_back(f[0], ab, ca);
      finer.emplace_back(f[1], bc, ab);
      finer.emplace_back(f[2], ca, bc);
      finer.emplace_back(ab, bc, ca);
    }
    faces = std::move(finer);
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(unit.size());
  for (const auto& v : unit) {
    add_vertex(mesh, v.x() * radii.x(), v.y() * radii.y(), v.z() * radii.z());
  }
  mesh.triangles = std::move(faces);
  return mesh;
}

TriangleMesh make_ground_square(double half_extent, double z) {
  require(std::isfinite(half_extent) && half_extent > 0.0 && std::isfinite(z),
          "ground needs half_extent > 0");
  TriangleMesh mesh;
  add_vertex(mesh, -half_extent, -half_extent, z);
  add_vertex(mesh, half_extent, -half_extent, z);
  add_vertex(mesh, half_extent, half_extent, z);
  add_vertex(mesh, -half_extent, half_extent, z);
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

std::vector<Eigen::Vector2d> rounded_rectangle(double cx, double cy, double hx, double hy, double r,
                                               int arc_segments) {
  require(
      std::isfinite(cx) && std::isfinite(cy) && std::isfinite(hx) && std::isfinite(hy) && std::isfinite(r),
      "rounded rectangle needs finite parameters");
  require(hx > 0.0 && hy > 0.0 && r >= 0.0 && r <= std::min(hx, hy) && arc_segments >= 1,
          "rounded rectangle needs 0 <= r <= min(hx, hy) and >= 1 arc segment");
  // Corner centres counter-clockwise from (+x, +y); each arc spans the quarter turn that starts at
  // the corner's index * 90 deg, so the arc end points are the straight sides' tangent points.
  const std::array<Eigen::Vector2d, 4> signs = {{{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}};
  std::vector<Eigen::Vector2d> ring;
  ring.reserve(4 * static_cast<std::size_t>(arc_segments + 1));
  for (int corner = 0; corner < 4; ++corner) {
    const Eigen::Vector2d centre(cx + signs[static_cast<std::size_t>(corner)].x() * (hx - r),
                                 cy + signs[static_cast<std::size_t>(corner)].y() * (hy - r));
    for (int j = 0; j <= arc_segments; ++j) {
      const double a = 0.5 * kPi * (corner + static_cast<double>(j) / arc_segments);
      Eigen::Vector2d p = centre + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      // Snap the tangent points so the extreme coordinates are exact (footprint = length x width).
      if (j == 0 || j == arc_segments) {
        const bool on_x_side = (corner % 2 == 0) == (j == 0);
        if (on_x_side) {
          p.x() = cx + signs[static_cast<std::size_t>(corner)].x() * hx;
        } else {
          p.y() = cy + signs[static_cast<std::size_t>(corner)].y() * hy;
        }
      }
      ring.push_back(p);
    }
  }
  return ring;
}

std::vector<Eigen::Vector2d> clip_polygon_x(const std::vector<Eigen::Vector2d>& convex_ccw, double x_min,
                                            double x_max) {
  require(x_min < x_max, "clip_polygon_x needs x_min < x_max");
  auto clip = [](const std::vector<Eigen::Vector2d>& poly, double bound, double side) {
    // Keeps points with side * (x - bound) >= 0.
    std::vector<Eigen::Vector2d> out;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d& p = poly[i];
      const Eigen::Vector2d& q = poly[(i + 1) % n];
      const double dp = side * (p.x() - bound);
      const double dq = side * (q.x() - bound);
      if (dp >= 0.0) {
        out.push_back(p);
      }
      if ((dp >= 0.0) != (dq >= 0.0)) {
        const double s = dp / (dp - dq);
        Eigen::Vector2d cut = p + s * (q - p);
        cut.x() = bound;
        out.push_back(cut);
      }
    }
    // Drop consecutive duplicates left where a vertex lay exactly on the bound.
    std::vector<Eigen::Vector2d> unique;
    for (const auto& p : out) {
      if (unique.empty() || (p - unique.back()).norm() > 1e-9) {
        unique.push_back(p);
      }
    }
    while (unique.size() > 1 && (unique.front() - unique.back()).norm() <= 1e-9) {
      unique.pop_back();
    }
    return unique;
  };
  return clip(clip(convex_ccw, x_min, 1.0), x_max, -1.0);
}

}  // namespace rsu::sim
