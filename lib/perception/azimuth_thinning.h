// SPDX-License-Identifier: Apache-2.0
// A dense cluster thinned along azimuth before its fix (issue 16 item 1). A car 3.6-10 m from a 128-ring
// sensor 2 m up holds 3,600-20,200 points, and its fix (the L-shape criterion, the faces' EM, run again at
// each yaw probe) cost 1.8-8.9 ms of CPU (bench_perception BM_FixVehicleNear) against the 0.78 ms between
// an OS1-128's packets; the fix needs far fewer.
//
// What is kept is what the correction reasons with:
//  - every laser: the correction asks per laser what the LiDAR could have seen (lidar_geometry.h: a laser
//    that would have hit the body and returned nothing says the body is not there), so thinning never
//    drops a laser; it thins along each laser's trace only, keeping every k-th of its azimuth columns;
//  - the ends of each trace, and the points beside a break in it (two or more columns without a return):
//    the body ends within an azimuth step of them (box_axis.h, CorrectionConfig::max_end_spacing_m);
// and what is lost is said: along a trace the points then lie k azimuth steps apart, the spacing the fix
// states (VehicleFix::azimuth_stride, the covariance's azimuth resolution).
//
// A laser's trace is told from its neighbours by the lasers' elevations (the nearest, as
// LidarGeometry::laser_of); without them nothing is thinned. Columns are the points' azimuth seen from
// the LiDAR in steps of LidarGeometry::azimuth_step_rad, counted from the laser's own first point, so that
// a beam's azimuth offset (an Ouster's beams are up to ~3 deg apart) does not put it between two columns.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "perception/lidar_geometry.h"

namespace rsu::perception {

struct AzimuthThinning {
  // Every k-th column of each laser's trace is kept; 1: nothing was thinned (points is then empty: the
  // input stands as it is).
  int stride = 1;
  std::vector<Eigen::Vector3d> points;  // the points kept, in their input order (finite ones only)
};

// `points` thinned to about `max_points` (k = the finite points / max_points, rounded up, and the ends
// kept beside them) when more of them are finite, the lidar's elevations are known and its azimuth step
// positive; else stride 1.
AzimuthThinning thin_along_azimuth(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                                   std::size_t max_points);

// atan2(y, x) within 1e-10 rad, as the columns above are measured (float's atan2f, used before, is within
// ~1e-7: a column is the same); 0 for (0, 0).
//
// About half of the thinning's time went to atan2f (issue 16, bench_perception BM_ThinNear). The angle is
// folded to [0, pi/8] (octant symmetry, then atan(lo / hi) = pi/4 + atan((lo - hi) / (lo + hi)) above
// tan(pi/8)), where the Taylor series to t^21 leaves under 0.4142^23 / 23 ~ 1e-10. One division, and the
// series in Estrin's form (powers of t^2 side by side): Horner's chain of 11 dependent multiply-adds was as
// slow as atan2f. Inline, so that the thinning's pass over the angles inlines it.
inline double azimuth_angle(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double lo = std::min(ax, ay), hi = std::max(ax, ay);
  if (!(hi > 0.0))
    return 0.0;
  constexpr double kTanPiOver8 = 0.41421356237309503;
  const bool upper = lo > kTanPiOver8 * hi;
  const double t = upper ? (lo - hi) / (lo + hi) : lo / hi;  // |t| <= tan(pi/8)
  // The series' coefficients (-1)^k / (2k + 1), k = 0..10.
  static constexpr auto c = [] {
    std::array<double, 11> out{};
    for (std::size_t k = 0; k < out.size(); ++k)
      out[k] = (k % 2 == 0 ? 1.0 : -1.0) / static_cast<double>(2 * k + 1);
    return out;
  }();
  const double t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
  const double low = (c[0] + c[1] * t2) + t4 * (c[2] + c[3] * t2);
  const double mid = (c[4] + c[5] * t2) + t4 * (c[6] + c[7] * t2);
  const double high = (c[8] + c[9] * t2) + t4 * c[10];
  double a = t * (low + t8 * (mid + t8 * high)) + (upper ? std::numbers::pi / 4.0 : 0.0);
  if (ay > ax)
    a = std::numbers::pi / 2.0 - a;
  if (x < 0.0)
    a = std::numbers::pi - a;
  return std::signbit(y) ? -a : a;
}

}  // namespace rsu::perception
