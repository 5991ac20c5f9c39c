// SPDX-License-Identifier: Apache-2.0
// Independent geometry used by the sim tests as ground truth: mesh topology and volume, closest
// points on triangles, analytic ray intersections. Written here, not taken from sim/, so a test does
// not check the code under test against itself.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sim/mesh.h"

namespace rsu::sim::testing {

inline Eigen::Vector3d vertex(const TriangleMesh& m, int i) {
  return m.vertices[static_cast<std::size_t>(i)].cast<double>();
}

// Empty when every directed edge (a, b) occurs exactly once and its reverse (b, a) exactly once:
// the mesh is closed (watertight) and consistently oriented. Otherwise the first problem found.
inline std::string closed_mesh_problem(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      ++directed[{t[k], t[(k + 1) % 3]}];
    }
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) {
      return "edge " + std::to_string(edge.first) + "->" + std::to_string(edge.second) + " used " +
             std::to_string(count) + " times in the same direction";
    }
    const auto reverse = directed.find({edge.second, edge.first});
    if (reverse == directed.end()) {
      return "edge " + std::to_string(edge.first) + "->" + std::to_string(edge.second) + " has no twin";
    }
  }
  return {};
}

// Divergence theorem: sum of signed tetrahedra (origin, a, b, c); positive for outward winding.
inline double signed_volume(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) {
    v += vertex(m, t[0]).dot(vertex(m, t[1]).cross(vertex(m, t[2]))) / 6.0;
  }
  return v;
}

// Connected components (triangles sharing a vertex index), each as its own mesh.
inline std::vector<TriangleMesh> components(const TriangleMesh& m) {
  std::vector<int> parent(m.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      x = parent[static_cast<std::size_t>(x)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    }
    return x;
  };
  for (const auto& t : m.triangles) {
    parent[static_cast<std::size_t>(find(t[1]))] = find(t[0]);
    parent[static_cast<std::size_t>(find(t[2]))] = find(t[0]);
  }
  std::map<int, TriangleMesh> by_root;
  std::map<int, std::map<int, int>> remap;
  for (const auto& t : m.triangles) {
    const int root = find(t[0]);
    TriangleMesh& c = by_root[root];
    auto& r = remap[root];
    Eigen::Vector3i nt;
    for (int k = 0; k < 3; ++k) {
      auto it = r.find(t[k]);
      if (it == r.end()) {
        c.vertices.push_back(m.vertices[static_cast<std::size_t>(t[k])]);
        it = r.emplace(t[k], static_cast<int>(c.vertices.size()) - 1).first;
      }
      nt[k] = it->second;
    }
    c.triangles.push_back(nt);
  }
  std::vector<TriangleMesh> out;
  for (auto& [root, c] : by_root) {
    out.push_back(std::move(c));
  }
  return out;
}

// Closest point on triangle abc to p (Voronoi-region case analysis of the barycentric coordinates).
inline Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                 const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    return a;
  }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) {
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    return a + ab * (d1 / (d1 - d3));
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) {
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    return a + ac * (d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Distance from p to the nearest triangle of m (brute force).
inline double distance_to_mesh(const Eigen::Vector3d& p, const TriangleMesh& m) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d q = closest_point_on_triangle(p, vertex(m, t[0]), vertex(m, t[1]), vertex(m, t[2]));
    best = std::min(best, (p - q).norm());
  }
  return best;
}

// Nearest positive ray parameter where o + s d (d unit) meets the sphere |x - c| = r.
inline std::optional<double> ray_sphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                        const Eigen::Vector3d& c, double r) {
  const Eigen::Vector3d w = o - c;
  const double b = w.dot(d);
  const double disc = b * b - (w.squaredNorm() - r * r);
  if (disc < 0) {
    return std::nullopt;
  }
  const double s = -b - std::sqrt(disc);
  if (s > 0) {
    return s;
  }
  const double s2 = -b + std::sqrt(disc);
  return s2 > 0 ? std::optional<double>(s2) : std::nullopt;
}

// Slab test for an axis-aligned box [lo, hi]: entry parameter and the outward normal of the entry face.
struct BoxHit {
  double s;
  Eigen::Vector3d normal;
};
inline std::optional<BoxHit> ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                     const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double enter = 0.0;
  double leave = std::numeric_limits<double>::infinity();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < lo[k] || o[k] > hi[k]) {
        return std::nullopt;
      }
      continue;
    }
    double s0 = (lo[k] - o[k]) / d[k];
    double s1 = (hi[k] - o[k]) / d[k];
    const double sign = s0 < s1 ? -1.0 : 1.0;  // entering through lo (normal -e_k) or hi (+e_k)
    if (s0 > s1) {
      std::swap(s0, s1);
    }
    if (s0 > enter) {
      enter = s0;
      normal = Eigen::Vector3d::Zero();
      normal[k] = sign;
    }
    leave = std::min(leave, s1);
  }
  if (enter > leave || enter <= 0.0) {
    return std::nullopt;
  }
  return BoxHit{enter, normal};
}

}  // namespace rsu::sim::testing
