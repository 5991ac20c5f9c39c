// SPDX-License-Identifier: Apache-2.0
// Test-side ground truth: boxes the tests know exactly, and an independent little ray caster that
// samples what a LiDAR at a known position would see of them (2D for fitting, 3D for whole frames).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "lidar/point.h"
#include "perception/size_correction.h"

namespace rsu::perception::test {

constexpr double kPi = std::numbers::pi;

struct TrueBox {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double yaw = 0.0;  // of the length axis
  double length = 4.89;
  double width = 1.92;

  Eigen::Vector2d u() const { return {std::cos(yaw), std::sin(yaw)}; }
  Eigen::Vector2d v() const { return {-std::sin(yaw), std::cos(yaw)}; }
  std::array<Eigen::Vector2d, 4> corners() const {
    const Eigen::Vector2d a = u() * length / 2.0;
    const Eigen::Vector2d b = v() * width / 2.0;
    return {centre - a - b, centre + a - b, centre + a + b, centre - a + b};
  }
};

// Distance along the ray (origin o, unit direction d) to the box's outline, if hit.
inline std::optional<double> ray_hit(const TrueBox& box, const Eigen::Vector2d& o, const Eigen::Vector2d& d) {
  const auto c = box.corners();
  std::optional<double> best;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = c[static_cast<std::size_t>(k)];
    const Eigen::Vector2d e = c[static_cast<std::size_t>((k + 1) % 4)] - a;
    // o + t d = a + s e  ->  [d, -e] (t, s) = a - o
    const double det = d.x() * (-e.y()) - d.y() * (-e.x());
    if (std::abs(det) < 1e-12) {
      continue;
    }
    const Eigen::Vector2d rhs = a - o;
    const double t = (rhs.x() * (-e.y()) - rhs.y() * (-e.x())) / det;
    const double s = (d.x() * rhs.y() - d.y() * rhs.x()) / det;
    if (t > 0.0 && s >= 0.0 && s <= 1.0 && (!best || t < *best)) {
      best = t;
    }
  }
  return best;
}

// What a spinning LiDAR at `lidar` sees of the box in 2D: one ray every `step` radians (random phase),
// range noise sigma along the ray.
inline std::vector<Eigen::Vector2d> scan_box(const TrueBox& box, const Eigen::Vector2d& lidar, double step,
                                             double range_sigma, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0.0, step);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Vector2d> out;
  const double start = phase(rng);
  for (double a = start; a < 2.0 * kPi; a += step) {
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    if (const auto t = ray_hit(box, lidar, d)) {
      out.push_back(lidar + d * (*t + range_sigma * noise(rng)));
    }
  }
  return out;
}

// --- 3D frames ---------------------------------------------------------------------------------------

// A vehicle as a box standing on the ground (z from clearance to height), a ground plane z = 0 and a
// round wall of radius wall_radius around the LiDAR (a "street canyon" that closes every ray).
struct Scene3d {
  std::vector<TrueBox> vehicles;
  double vehicle_bottom = 0.2;
  double vehicle_top = 1.7;
  double wall_radius = 40.0;
  double wall_height = 15.0;
};

struct Lidar3d {
  Eigen::Vector3d position{0.0, 0.0, 2.0};
  std::vector<double> elevation_deg;  // per ring
  int azimuth_steps = 1800;
  double range_sigma = 0.02;
  double max_range = 100.0;
};

enum class HitKind { none, ground, wall, vehicle };

struct LabelledPoint {
  lidar::LidarPoint point;
  HitKind kind = HitKind::none;
};

// Ray against the scene: nearest of ground plane, wall cylinder (inside), vehicle boxes.
inline std::pair<double, HitKind> cast_3d(const Scene3d& scene, const Eigen::Vector3d& o,
                                          const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  HitKind kind = HitKind::none;
  if (d.z() < 0.0) {
    best = -o.z() / d.z();
    kind = HitKind::ground;
  }
  // Wall: |o_xy + t d_xy| = R, the root with t > 0.
  const Eigen::Vector2d oxy = o.head<2>();
  const Eigen::Vector2d dxy = d.head<2>();
  const double a = dxy.squaredNorm();
  if (a > 1e-12) {
    const double b = 2.0 * oxy.dot(dxy);
    const double c = oxy.squaredNorm() - scene.wall_radius * scene.wall_radius;
    const double t = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
    const double z = o.z() + t * d.z();
    if (t > 0.0 && t < best && z >= 0.0 && z <= scene.wall_height) {
      best = t;
      kind = HitKind::wall;
    }
  }
  for (const auto& box : scene.vehicles) {
    // Slabs in the box frame.
    const Eigen::Vector2d rel = oxy - box.centre;
    const double ox = rel.dot(box.u()), oy = rel.dot(box.v());
    const double dx = dxy.dot(box.u()), dy = dxy.dot(box.v());
    double t0 = 0.0, t1 = best;
    auto slab = [&](double origin, double dir, double lo, double hi) {
      if (std::abs(dir) < 1e-12) {
        return origin >= lo && origin <= hi;
      }
      double ta = (lo - origin) / dir, tb = (hi - origin) / dir;
      if (ta > tb)
        std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      return t0 <= t1;
    };
    if (slab(ox, dx, -box.length / 2, box.length / 2) && slab(oy, dy, -box.width / 2, box.width / 2) &&
        slab(o.z(), d.z(), scene.vehicle_bottom, scene.vehicle_top) && t0 > 0.0 && t0 < best) {
      best = t0;
      kind = HitKind::vehicle;
    }
  }
  return {best, kind};
}

// One frame: every ring at every azimuth step (phase `phase` in [0, 1) of a step), LidarPoint fields as
// the sources deliver them (map frame, ring, clockwise azimuth, firing time).
inline std::vector<LabelledPoint> scan_3d(const Scene3d& scene, const Lidar3d& lidar, double phase,
                                          std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<LabelledPoint> out;
  for (int s = 0; s < lidar.azimuth_steps; ++s) {
    const double az = (s + phase) * 2.0 * kPi / lidar.azimuth_steps;  // clockwise from +x
    for (std::size_t ring = 0; ring < lidar.elevation_deg.size(); ++ring) {
      const double el = lidar.elevation_deg[ring] * kPi / 180.0;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az), std::sin(el));
      const auto [t, kind] = cast_3d(scene, lidar.position, d);
      if (kind == HitKind::none || t > lidar.max_range) {
        continue;
      }
      const Eigen::Vector3d p = lidar.position + d * (t + lidar.range_sigma * noise(rng));
      LabelledPoint lp;
      lp.point.x = static_cast<float>(p.x());
      lp.point.y = static_cast<float>(p.y());
      lp.point.z = static_cast<float>(p.z());
      lp.point.ring = static_cast<std::uint16_t>(ring);
      lp.point.azimuth_rad = static_cast<float>(az);
      lp.point.time_ns = static_cast<TimeNs>(1'000'000 + s * 55'296);
      lp.kind = kind;
      out.push_back(lp);
    }
  }
  return out;
}

inline std::vector<lidar::LidarPoint> points_of(const std::vector<LabelledPoint>& labelled) {
  std::vector<lidar::LidarPoint> out;
  out.reserve(labelled.size());
  for (const auto& l : labelled) {
    out.push_back(l.point);
  }
  return out;
}

// What the fix needs to know of this LiDAR (lidar_geometry.h).
inline LidarGeometry geometry_of(const Lidar3d& l) {
  LidarGeometry g;
  g.position = l.position;
  for (const double e : l.elevation_deg)
    g.elevations_rad.push_back(e * kPi / 180.0);
  return g;
}

inline Lidar3d small_lidar(int rings = 16) {
  Lidar3d l;
  for (int i = 0; i < rings; ++i) {
    l.elevation_deg.push_back(-15.0 + 30.0 * i / (rings - 1));
  }
  return l;
}

// The improved correction on a flat scan (test::scan_box): every point on the lower body of a box of the
// default height (0.5 m up), the LiDAR at the same height, every direction observed.
inline CorrectedPose correct_flat(const RectangleFit& fit, const std::vector<Eigen::Vector2d>& points,
                                  const VehicleSize& size, const Eigen::Vector2d& lidar_xy,
                                  const std::optional<YawPrior>& prior, const CorrectionConfig& config = {}) {
  std::vector<Eigen::Vector3d> points3;
  points3.reserve(points.size());
  for (const auto& p : points)
    points3.emplace_back(p.x(), p.y(), 0.5);
  LidarGeometry lidar;
  lidar.position = {lidar_xy.x(), lidar_xy.y(), 0.5};
  return correct_improved(fit, points, points3, size, lidar, prior, config);
}

}  // namespace rsu::perception::test
