// SPDX-License-Identifier: Apache-2.0
#include "perception/informative_face.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

double median(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The length of an evenly spread face whose direction a line fit knows as well as it does from points at
// `along` (a least-squares slope's variance is sigma^2 / sum (s - mean)^2; evenly over l that sum is n l^2
// / 12): sqrt(12) times their RMS spread about their mean.
double effective_face_length(std::span<const double> along) {
  if (along.size() < 2)
    return 0.0;
  double mean = 0.0;
  for (const double s : along)
    mean += s;
  mean /= static_cast<double>(along.size());
  double sum_sq = 0.0;
  for (const double s : along)
    sum_sq += (s - mean) * (s - mean);
  return std::sqrt(12.0 * sum_sq / static_cast<double>(along.size()));
}

}  // namespace

FaceEvidence informative_face(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                              const CorrectionConfig& config, double end_height, double noise_sigma,
                              const RectangleFit& fit, std::size_t edge) {
  FaceEvidence face = face_evidence(fit, edge, lidar.xy());
  const Eigen::Vector2d a = fit.corners[edge % 4];
  const Eigen::Vector2d b = fit.corners[(edge + 1) % 4];
  const double len = (b - a).norm();
  const Eigen::Vector2d t = (b - a) / len;
  const double d = config.fit.edge_support_m;
  std::vector<double> across, upper_heights, upper_ranges;
  // Where along the face its informative points lie (below the bonnet; above it those that count), for
  // the extent they span.
  std::vector<double> along, upper_along;
  std::size_t lower = 0;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector2d r = p.head<2>() - a;
    const double s = r.dot(t);
    const double n = r.x() * t.y() - r.y() * t.x();
    if (s < -d || s > len + d || std::abs(n) > d)
      continue;
    across.push_back(n);
    if (p.z() - lidar.ground_z <= end_height) {
      ++lower;
      along.push_back(s);
    } else {
      upper_heights.push_back(p.z());
      upper_ranges.push_back((p.head<2>() - lidar.xy()).norm());
      upper_along.push_back(s);
    }
  }
  // Above the lower body a face tells the direction if it is not a laser's trace on a level surface:
  // it rises (several heights), or its points' horizontal ranges vary (a level surface cut by one laser
  // is an arc at one range, across the line of sight whatever the vehicle's heading).
  std::size_t informative = lower;
  if (upper_heights.size() >= 3) {
    const double top = *std::max_element(upper_heights.begin(), upper_heights.end());
    const auto rising =
        static_cast<std::size_t>(std::count_if(upper_heights.begin(), upper_heights.end(), [&](double z) {
          return z <= top - config.min_vertical_spread_m;
        }));
    std::sort(upper_ranges.begin(), upper_ranges.end());
    const auto at = [&](double q) {
      return upper_ranges[static_cast<std::size_t>(q * static_cast<double>(upper_ranges.size() - 1))];
    };
    const double arc_tolerance = std::max(config.min_range_spread_m, 4.0 * noise_sigma);
    if (at(0.9) - at(0.1) >= arc_tolerance) {
      informative += upper_heights.size();
      along.insert(along.end(), upper_along.begin(), upper_along.end());
    } else if (rising >= 3) {
      informative += rising;
      for (std::size_t i = 0; i < upper_heights.size(); ++i) {
        if (upper_heights[i] <= top - config.min_vertical_spread_m)
          along.push_back(upper_along[i]);
      }
    }
  }
  // The upper body departs from the footprint's direction more than the lower body does (sloped glass,
  // tumblehome): its faces' direction is trusted less.
  if (upper_heights.size() >= lower)
    face.departure_m = config.upper_face_tilt_m;
  face.points = informative;
  // The face's direction is as well known as its informative points' spread along it makes it, not the
  // fitted edge's length: a few points on a rounded bumper's corner made a 1.7 m "face" 24 deg off while
  // stating 2 deg (`rsu-pilot matrix`, a VLP-16 4 m up, an SUV at 25 m).
  face.length_m = std::min(face.length_m, effective_face_length(along));
  if (face.length_m < config.short_face_m)
    face.departure_m = std::max(face.departure_m, config.short_face_tilt_m);
  if (across.size() >= 3 && informative > 0) {
    // Robust spread (1.4826 MAD) of the face's points about their median line: the body's departure.
    const double centre = median(across);
    for (double& x : across)
      x = std::abs(x - centre);
    face.residual_spread_m = 1.4826 * median(across);
  }
  return face;
}

}  // namespace rsu::perception
