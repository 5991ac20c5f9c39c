// SPDX-License-Identifier: Apache-2.0
#include "perception/convex_hull.h"

#include <algorithm>
#include <array>
#include <limits>

namespace rsu::perception {
namespace {

// Twice the signed area of (o, a, b): positive when b lies left of the line o -> a. In double: the
// products of float coordinates are exact there, so the sign is exact.
double cross(double ox, double oy, double ax, double ay, double bx, double by) {
  return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox);
}

// The same for the points o, a and b of the coordinate spans.
double cross(std::span<const float> x, std::span<const float> y, std::size_t o, std::size_t a,
             std::size_t b) {
  const auto at = [](std::span<const float> c, std::size_t i) { return static_cast<double>(c[i]); };
  return cross(at(x, o), at(y, o), at(x, a), at(y, a), at(x, b), at(y, b));
}

// The points that may be hull vertices: all but those strictly inside the octagon of the extreme points
// along the directions 180, 225, ..., 135 deg. As the direction turns counter-clockwise its extreme
// point walks the hull counter-clockwise, so these eight (repeats removed) are a convex polygon in order.
std::vector<std::size_t> outside_octagon(std::span<const float> x, std::span<const float> y) {
  const std::size_t n = x.size();
  constexpr std::array<std::array<double, 2>, 8> kDirections = {
      {{-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}, {1, 1}, {0, 1}, {-1, 1}}};
  std::array<std::size_t, 8> extreme{};
  std::array<double, 8> best{};
  best.fill(-std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < n; ++i) {
    const auto px = static_cast<double>(x[i]);
    const auto py = static_cast<double>(y[i]);
    for (std::size_t d = 0; d < 8; ++d) {
      const double v = kDirections[d][0] * px + kDirections[d][1] * py;
      if (v > best[d]) {
        best[d] = v;
        extreme[d] = i;
      }
    }
  }
  std::vector<std::size_t> polygon;
  for (const std::size_t e : extreme) {
    if (polygon.empty() || (x[e] != x[polygon.back()] || y[e] != y[polygon.back()]))
      polygon.push_back(e);
  }
  while (polygon.size() > 1 && x[polygon.front()] == x[polygon.back()] &&
         y[polygon.front()] == y[polygon.back()])
    polygon.pop_back();
  std::vector<std::size_t> kept;
  if (polygon.size() < 3) {
    kept.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      kept[i] = i;
    return kept;
  }
  for (std::size_t i = 0; i < n; ++i) {
    bool inside = true;
    for (std::size_t k = 0; k < polygon.size() && inside; ++k) {
      const std::size_t a = polygon[k];
      const std::size_t b = polygon[(k + 1) % polygon.size()];
      inside = cross(x, y, a, b, i) > 0.0;
    }
    if (!inside)
      kept.push_back(i);
  }
  return kept;
}

}  // namespace

std::vector<std::size_t> convex_hull_vertices(std::span<const float> x, std::span<const float> y) {
  if (x.empty() || y.empty())
    return {};  // the octagon's extremes would name point 0
  std::vector<std::size_t> candidates = outside_octagon(x.first(std::min(x.size(), y.size())), y);
  std::sort(candidates.begin(), candidates.end(),
            [&](std::size_t a, std::size_t b) { return x[a] < x[b] || (x[a] == x[b] && y[a] < y[b]); });
  candidates.erase(std::unique(candidates.begin(), candidates.end(),
                               [&](std::size_t a, std::size_t b) { return x[a] == x[b] && y[a] == y[b]; }),
                   candidates.end());
  if (candidates.size() < 3)
    return candidates;
  // Lower chain left to right, then upper chain right to left; each drops points that do not turn left.
  std::vector<std::size_t> hull(2 * candidates.size());
  std::size_t k = 0;
  auto turns_left = [&](std::size_t o, std::size_t a, std::size_t b) { return cross(x, y, o, a, b) > 0.0; };
  for (const std::size_t i : candidates) {
    while (k >= 2 && !turns_left(hull[k - 2], hull[k - 1], i))
      --k;
    hull[k++] = i;
  }
  const std::size_t lower = k + 1;
  for (auto it = candidates.rbegin() + 1; it != candidates.rend(); ++it) {
    while (k >= lower && !turns_left(hull[k - 2], hull[k - 1], *it))
      --k;
    hull[k++] = *it;
  }
  hull.resize(k - 1);  // the last is the first again
  return hull;
}

}  // namespace rsu::perception
