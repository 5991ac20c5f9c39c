// SPDX-License-Identifier: Apache-2.0
#include "perception/box_consistency.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "perception/size_correction.h"

namespace rsu::perception {
namespace {

struct Coverage {
  double expected = 0.0;
  double missing = 0.0;
};

// The outline of the box's face at coordinate `face` on axis a, seen from `towards` away: which of its
// bins no point covers, weighted by the cosine of incidence (faces seen edge-on are not expected).
void face_coverage(std::span<const Eigen::Vector2d> local, const Eigen::Vector2d& lidar_local,
                   const Eigen::Vector2d& centre, const Eigen::Vector2d& half, int a, double face,
                   double towards, double cover_radius, const CorrectionConfig& config, Coverage& coverage) {
  const int b = 1 - a;
  const double from = centre[b] - half[b];
  const double length = 2.0 * half[b];
  const auto bins = static_cast<std::size_t>(std::max(1.0, std::ceil(length / config.face_bin_m)));
  const double bin = length / static_cast<double>(bins);
  std::vector<bool> covered(bins, false);
  for (const auto& p : local) {
    if (std::abs(p[a] - face) > cover_radius)
      continue;
    const double t0 = (p[b] - cover_radius - from) / bin;
    const double t1 = (p[b] + cover_radius - from) / bin;
    if (t1 < 0.0 || t0 >= static_cast<double>(bins))
      continue;
    const auto j0 = static_cast<std::size_t>(std::max(0.0, std::floor(t0)));
    const auto j1 = std::min(bins - 1, static_cast<std::size_t>(std::floor(t1)));
    for (std::size_t j = j0; j <= j1; ++j)
      covered[j] = true;
  }
  for (std::size_t j = 0; j < bins; ++j) {
    const double t = from + (static_cast<double>(j) + 0.5) * bin;
    const double along = lidar_local[b] - t;
    const double cos_incidence = towards / std::sqrt(towards * towards + along * along);
    if (cos_incidence < config.min_incidence_cos)
      continue;
    coverage.expected += cos_incidence;
    if (!covered[j])
      coverage.missing += cos_incidence;
  }
}

}  // namespace

double outside_fraction(std::span<const Eigen::Vector2d> local, const Eigen::Vector2d& centre,
                        const Eigen::Vector2d& half, double tolerance) {
  if (local.empty())
    return 0.0;
  const auto outside = std::count_if(local.begin(), local.end(), [&](const Eigen::Vector2d& p) {
    return ((p - centre).cwiseAbs() - half).maxCoeff() > tolerance;
  });
  return static_cast<double>(outside) / static_cast<double>(local.size());
}

double box_inconsistency(std::span<const Eigen::Vector2d> local, const Eigen::Vector2d& lidar_local,
                         const Eigen::Vector2d& centre, const Eigen::Vector2d& half, double cover_radius,
                         const CorrectionConfig& config) {
  Coverage coverage;
  for (int a = 0; a < 2; ++a) {
    for (const double side : {-1.0, 1.0}) {
      const double face = centre[a] + side * half[a];
      const double towards = side * (lidar_local[a] - face);
      if (towards > 0.0)
        face_coverage(local, lidar_local, centre, half, a, face, towards, cover_radius, config, coverage);
    }
  }
  const double uncovered = coverage.expected > 0.0 ? coverage.missing / coverage.expected : 1.0;
  return outside_fraction(local, centre, half, config.outside_tolerance_m) + uncovered;
}

}  // namespace rsu::perception
