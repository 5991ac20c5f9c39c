// SPDX-License-Identifier: Apache-2.0
// convex_hull_vertices against a brute-force definition of a hull vertex: a point that does not lie in the
// closed convex hull of the other points (by Carathéodory, in no closed triangle of three of them), on
// integer coordinates where every test is exact. Then its promises on dense clusters of real coordinates:
// counter-clockwise, strictly convex, every point inside or on it.
#include "perception/convex_hull.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace rsu::perception {
namespace {

using Point = std::pair<std::int64_t, std::int64_t>;

std::int64_t cross(const Point& o, const Point& a, const Point& b) {
  return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
}

// The hull's vertices by definition: the distinct points not in the closed hull of the other distinct
// ones. p lies outside the hull of a set exactly when the set lies in an open half-plane through p: when
// one of the vectors from p to the others has all the rest strictly to its left or on its own ray.
std::set<Point> reference_vertices(const std::vector<Point>& points) {
  const std::set<Point> distinct_set(points.begin(), points.end());
  const std::vector<Point> distinct(distinct_set.begin(), distinct_set.end());
  std::set<Point> out;
  for (const Point& p : distinct) {
    std::vector<Point> v;
    for (const Point& q : distinct) {
      if (q != p)
        v.emplace_back(q.first - p.first, q.second - p.second);
    }
    const Point origin{0, 0};
    const bool outside = v.empty() || std::any_of(v.begin(), v.end(), [&](const Point& edge) {
                           return std::all_of(v.begin(), v.end(), [&](const Point& w) {
                             const std::int64_t c = cross(origin, edge, w);
                             return c > 0 || (c == 0 && edge.first * w.first + edge.second * w.second > 0);
                           });
                         });
    if (outside)
      out.insert(p);
  }
  return out;
}

struct Cloud {
  std::vector<float> x, y;
};

Cloud to_floats(const std::vector<Point>& points) {
  Cloud c;
  for (const Point& p : points) {
    c.x.push_back(static_cast<float>(p.first));
    c.y.push_back(static_cast<float>(p.second));
  }
  return c;
}

// The output as points, checked to be valid, distinct indices.
std::vector<Point> hull_points(const std::vector<Point>& points, const std::vector<std::size_t>& hull) {
  std::vector<Point> out;
  std::set<std::size_t> seen;
  for (const std::size_t i : hull) {
    EXPECT_LT(i, points.size());
    EXPECT_TRUE(seen.insert(i).second) << "index " << i << " twice";
    if (i < points.size())
      out.push_back(points[i]);
  }
  return out;
}

void expect_strictly_convex_ccw(const std::vector<Point>& polygon) {
  if (polygon.size() < 3)
    return;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const Point& o = polygon[k];
    const Point& a = polygon[(k + 1) % polygon.size()];
    const Point& b = polygon[(k + 2) % polygon.size()];
    EXPECT_GT(cross(o, a, b), 0) << "vertex " << k + 1 << " of " << polygon.size();
  }
}

void expect_hull_of(const std::vector<Point>& points) {
  const Cloud c = to_floats(points);
  const std::vector<Point> got = hull_points(points, convex_hull_vertices(c.x, c.y));
  const std::set<Point> want = reference_vertices(points);
  const std::set<Point> got_set(got.begin(), got.end());
  EXPECT_EQ(got_set.size(), got.size()) << "a vertex given twice";
  if (want.size() >= 3) {
    EXPECT_EQ(got_set, want);
    expect_strictly_convex_ccw(got);
  } else {
    // Fewer than three distinct points, or all on one line: the definition leaves the extreme ones
    // (one or two); the function promises the distinct points when there are fewer than three.
    const std::set<Point> distinct(points.begin(), points.end());
    if (distinct.size() < 3)
      EXPECT_EQ(got_set, distinct);
    else
      EXPECT_EQ(got_set, want) << "collinear: the two ends";
  }
}

TEST(ConvexHull, DegenerateInputs) {
  EXPECT_TRUE(convex_hull_vertices({}, {}).empty());
  expect_hull_of({{3, 4}});
  expect_hull_of({{3, 4}, {3, 4}, {3, 4}});
  expect_hull_of({{0, 0}, {5, 1}});
  expect_hull_of({{0, 0}, {5, 1}, {0, 0}, {5, 1}});
  expect_hull_of({{0, 0}, {1, 1}, {2, 2}, {3, 3}, {-4, -4}});  // collinear
  expect_hull_of({{0, 0}, {0, 7}, {0, 3}, {0, 7}});            // collinear, vertical, repeated
}

TEST(ConvexHull, CollinearPointsOnEdgesAndDuplicatesAreNotVertices) {
  // A 4 x 2 rectangle with every integer point of its outline and inside, each corner twice.
  std::vector<Point> grid;
  for (std::int64_t x = 0; x <= 4; ++x)
    for (std::int64_t y = 0; y <= 2; ++y)
      grid.emplace_back(x, y);
  grid.insert(grid.end(), {{0, 0}, {4, 2}, {4, 0}, {0, 2}});
  expect_hull_of(grid);
  const Cloud c = to_floats(grid);
  EXPECT_EQ(convex_hull_vertices(c.x, c.y).size(), 4U);
}

TEST(ConvexHull, MatchesTheDefinitionOnRandomIntegerClouds) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = std::uniform_int_distribution<int>(3, 40)(rng);
    const std::int64_t span = trial % 3 == 0 ? 3 : trial % 3 == 1 ? 20 : 1000;  // many repeats, few, none
    std::uniform_int_distribution<std::int64_t> coord(-span, span);
    std::vector<Point> points;
    for (int i = 0; i < n; ++i)
      points.emplace_back(coord(rng), coord(rng));
    SCOPED_TRACE("trial " + std::to_string(trial));
    expect_hull_of(points);
  }
}

// The lattice points of a disc: many candidates survive the octagon, and the chains decide among
// nearly collinear ones.
TEST(ConvexHull, LatticeDiscMatchesTheDefinition) {
  std::vector<Point> ring;
  for (std::int64_t x = -10; x <= 10; ++x) {
    for (std::int64_t y = -10; y <= 10; ++y) {
      if (x * x + y * y <= 100)
        ring.emplace_back(x, y);
    }
  }
  const std::set<Point> want = reference_vertices(ring);
  const Cloud c = to_floats(ring);
  const std::vector<Point> got = hull_points(ring, convex_hull_vertices(c.x, c.y));
  EXPECT_EQ(std::set<Point>(got.begin(), got.end()), want);
  EXPECT_GT(want.size(), 8U);
  expect_strictly_convex_ccw(got);
}

// A dense, vehicle-like cluster of real coordinates (an L of two faces with noise, and a roof): the hull
// holds every point, turns left at every vertex, and uses input points only.
TEST(ConvexHull, DenseRealClusterIsHeldByItsHull) {
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0F, 0.02F);
  std::uniform_real_distribution<float> u(0.0F, 1.0F);
  Cloud c;
  for (int i = 0; i < 6000; ++i) {
    const float t = u(rng);
    float px = 0, py = 0;
    if (i % 3 == 0) {
      px = 10.0F + 4.8F * t;  // the long face
      py = 3.0F;
    } else if (i % 3 == 1) {
      px = 10.0F;  // the short face
      py = 3.0F + 1.9F * t;
    } else {
      px = 10.0F + 4.8F * t;  // the roof
      py = 3.0F + 1.9F * u(rng);
    }
    c.x.push_back(px + noise(rng));
    c.y.push_back(py + noise(rng));
  }
  const std::vector<std::size_t> hull = convex_hull_vertices(c.x, c.y);
  ASSERT_GE(hull.size(), 4U);
  EXPECT_LT(hull.size(), 200U);
  const auto at = [&](std::size_t i) { return std::pair<double, double>(c.x[i], c.y[i]); };
  const auto turn = [](std::pair<double, double> o, std::pair<double, double> a,
                       std::pair<double, double> b) {
    return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
  };
  for (std::size_t k = 0; k < hull.size(); ++k) {
    ASSERT_LT(hull[k], c.x.size());
    EXPECT_GT(turn(at(hull[k]), at(hull[(k + 1) % hull.size()]), at(hull[(k + 2) % hull.size()])), 0.0);
  }
  for (std::size_t i = 0; i < c.x.size(); ++i) {
    for (std::size_t k = 0; k < hull.size(); ++k)
      ASSERT_GE(turn(at(hull[k]), at(hull[(k + 1) % hull.size()]), at(i)), -1e-9) << "point " << i;
  }
}

}  // namespace
}  // namespace rsu::perception
