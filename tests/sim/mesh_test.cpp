// SPDX-License-Identifier: Apache-2.0
#include "sim/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "geometry_checks.h"

namespace rsu::sim {
namespace {

using testing::closed_mesh_problem;
using testing::signed_volume;

TEST(SimMesh, BoxIsClosedOutwardAndHasItsVolume) {
  const TriangleMesh box = make_box({-1.0, -2.0, 0.0}, {3.0, 1.0, 2.5});
  EXPECT_EQ(box.triangles.size(), 12U);
  EXPECT_EQ(closed_mesh_problem(box), "");
  EXPECT_NEAR(signed_volume(box), 4.0 * 3.0 * 2.5, 1e-5);
  // Every face normal points away from the centre.
  const Eigen::Vector3d centre(1.0, -0.5, 1.25);
  for (const auto& t : box.triangles) {
    const Eigen::Vector3d a = testing::vertex(box, t[0]);
    const Eigen::Vector3d n = (testing::vertex(box, t[1]) - a).cross(testing::vertex(box, t[2]) - a);
    EXPECT_GT(n.dot(a - centre), 0.0);
  }
}

TEST(SimMesh, CylinderIsTheInscribedPolygonPrism) {
  const int n = 12;
  const double r = 0.4;
  const TriangleMesh c = make_cylinder(r, 1.0, 4.0, n);
  EXPECT_EQ(closed_mesh_problem(c), "");
  // Area of a regular n-gon with circumradius r: n/2 r^2 sin(2 pi / n).
  const double area = 0.5 * n * r * r * std::sin(2.0 * std::numbers::pi / n);
  EXPECT_NEAR(signed_volume(c), area * 3.0, 1e-5);
  for (const auto& v : c.vertices) {
    EXPECT_NEAR(std::hypot(v.x(), v.y()), r, 1e-6);
    EXPECT_TRUE(std::abs(v.z() - 1.0F) < 1e-6F || std::abs(v.z() - 4.0F) < 1e-6F);
  }
}

TEST(SimMesh, EllipsoidVerticesOnSurfaceClosedAndVolumeBelowTrueVolume) {
  const Eigen::Vector3d radii(2.0, 1.0, 0.5);
  for (int level = 0; level <= 3; ++level) {
    const TriangleMesh e = make_ellipsoid(radii, level);
    EXPECT_EQ(e.triangles.size(), 20U * (1U << (2 * level)));
    EXPECT_EQ(closed_mesh_problem(e), "") << "level " << level;
    for (const auto& v : e.vertices) {
      const Eigen::Vector3d q = v.cast<double>().cwiseQuotient(radii);
      EXPECT_NEAR(q.norm(), 1.0, 1e-6);
    }
    // Inscribed polyhedron: its volume is below the ellipsoid's and approaches it as it refines.
    const double truth = 4.0 / 3.0 * std::numbers::pi * radii.prod();
    EXPECT_LT(signed_volume(e), truth);
    EXPECT_GT(signed_volume(e), (level >= 3 ? 0.98 : 0.5) * truth);
  }
}

TEST(SimMesh, GroundSquareFacesUp) {
  const TriangleMesh g = make_ground_square(50.0, 0.0);
  ASSERT_EQ(g.triangles.size(), 2U);
  for (const auto& t : g.triangles) {
    const Eigen::Vector3d a = testing::vertex(g, t[0]);
    const Eigen::Vector3d n = (testing::vertex(g, t[1]) - a).cross(testing::vertex(g, t[2]) - a);
    EXPECT_GT(n.z(), 0.0);
  }
  double area = 0.0;
  for (const auto& t : g.triangles) {
    const Eigen::Vector3d a = testing::vertex(g, t[0]);
    area += 0.5 * (testing::vertex(g, t[1]) - a).cross(testing::vertex(g, t[2]) - a).norm();
  }
  EXPECT_NEAR(area, 100.0 * 100.0, 1e-3);
}

TEST(SimMesh, RoundedRectangleHasExactExtentsAndIsConvexCounterClockwise) {
  const auto ring = rounded_rectangle(1.0, -2.0, 2.5, 1.0, 0.3, 6);
  ASSERT_EQ(ring.size(), 4U * 7U);
  double x_min = 1e9, x_max = -1e9, y_min = 1e9, y_max = -1e9;
  for (const auto& p : ring) {
    x_min = std::min(x_min, p.x());
    x_max = std::max(x_max, p.x());
    y_min = std::min(y_min, p.y());
    y_max = std::max(y_max, p.y());
  }
  EXPECT_DOUBLE_EQ(x_min, -1.5);
  EXPECT_DOUBLE_EQ(x_max, 3.5);
  EXPECT_DOUBLE_EQ(y_min, -3.0);
  EXPECT_DOUBLE_EQ(y_max, -1.0);
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d e1 = ring[(i + 1) % ring.size()] - ring[i];
    const Eigen::Vector2d e2 = ring[(i + 2) % ring.size()] - ring[(i + 1) % ring.size()];
    EXPECT_GE(e1.x() * e2.y() - e1.y() * e2.x(), -1e-12) << "turns clockwise at " << i;
  }
  // The corner point itself is cut off by r (1 - 1/sqrt 2) at least.
  for (const auto& p : ring) {
    EXPECT_GT((p - Eigen::Vector2d(3.5, -1.0)).norm(), 0.3 * (std::sqrt(2.0) - 1.0) - 1e-9);
  }
}

TEST(SimMesh, ClipPolygonKeepsTheSlab) {
  const std::vector<Eigen::Vector2d> square = {{2, -1}, {2, 1}, {-2, 1}, {-2, -1}};
  const auto clipped = clip_polygon_x(square, -0.5, 1.0);
  double area = 0.0;
  for (std::size_t i = 0; i < clipped.size(); ++i) {
    const auto& p = clipped[i];
    const auto& q = clipped[(i + 1) % clipped.size()];
    area += 0.5 * (p.x() * q.y() - q.x() * p.y());
    EXPECT_GE(p.x(), -0.5);
    EXPECT_LE(p.x(), 1.0);
  }
  EXPECT_NEAR(area, 1.5 * 2.0, 1e-12);  // positive: still counter-clockwise
  EXPECT_EQ(clipped.size(), 4U);
}

TEST(SimMesh, AppendAndTransformKeepComponentsClosed) {
  TriangleMesh m = make_box({0, 0, 0}, {1, 1, 1});
  m.append(make_sphere(0.5, 1));
  EXPECT_EQ(closed_mesh_problem(m), "");
  const double volume = signed_volume(m);
  const Eigen::Affine3d t = Eigen::Translation3d(5, -3, 2) * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ());
  m.transform(t);
  EXPECT_NEAR(signed_volume(m), volume, 1e-4);  // rigid motion keeps volume and orientation
  EXPECT_EQ(testing::components(m).size(), 2U);
}

TEST(SimMesh, BadInputThrows) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(make_box({0, 0, 0}, {nan, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_box({0, 0, 0}, {-1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(make_cylinder(0.0, 0, 1), std::invalid_argument);
  EXPECT_THROW(make_cylinder(1.0, 0, 1, 2), std::invalid_argument);
  EXPECT_THROW(make_ellipsoid({1, nan, 1}), std::invalid_argument);
  EXPECT_THROW(make_ground_square(-1.0), std::invalid_argument);
  EXPECT_THROW(rounded_rectangle(0, 0, 1, 1, 2, 4), std::invalid_argument);
  EXPECT_THROW(make_loft({{0, 0}, {1, 0}, {0, 1}}, 0, {{0, 0}, {1, 0}}, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rsu::sim
