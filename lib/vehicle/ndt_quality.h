// SPDX-License-Identifier: Apache-2.0
// How the vehicle's own scan matching says it did, per pose: the quality indicator that lets the vehicle
// know when its own localization is the one that failed (and only then lets RSU fixes take over the
// pose). PCL's NDT (and Autoware's ndt_scan_matcher around it) gives three: whether the Newton iteration
// converged before its iteration cap, how many iterations it used, and the fitness score (mean squared
// distance of the aligned scan's points to their nearest map points); a fourth, the degeneracy, comes
// from the curvature of the match's score at its solution (eval/corridor/ndt_localizer.h). A pose
// without an indicator is taken at its word (its covariance stands): the vehicle's own sensor is
// trusted until it says otherwise.
#pragma once

#include <optional>

namespace rsu::vehicle {

struct NdtQuality {
  std::optional<bool> converged;  // false: stopped at the iteration cap, or no solution
  std::optional<int> iterations;
  std::optional<double> fitness_m2;  // mean squared point-to-map distance, m^2
  // sqrt(largest / smallest eigenvalue) of the match score's curvature in x, y at the solution: how many
  // times more weakly the match holds the vehicle in its weakest horizontal direction than in its
  // strongest. The fitness cannot see a street with nothing along it (sliding along a uniform facade fits
  // as well); this can.
  std::optional<double> degeneracy;
  // The direction of that weakest hold (rad, map frame, modulo pi): the eigenvector of the curvature's
  // smallest eigenvalue, along the street where nothing holds the match. A pose degraded by its
  // degeneracy alone is weakened along it only: across it and in yaw the match still holds (the
  // degraded corridor's NDT: 0.157 m MAE along the road, 0.026 m across).
  std::optional<double> weak_axis_rad;
};

struct NdtQualityLimits {
  // A match that used this many iterations hit the cap (Autoware's max_iterations: 30): not converged.
  int max_iterations = 30;
  // Fitness above this: the scan does not fit the map where NDT put it. In the corridor experiment a
  // healthy NDT measured a median of 0.047 m^2 and at most 0.36 m^2 (with its worst pose, 0.30 m off).
  double max_fitness_m2 = 0.5;
  // Degeneracy above this: the match holds the vehicle along some direction too weakly to be taken at
  // its covariance. Measured (README): the corridor, where NDT holds (lamp poles every 25 m), median 5.2,
  // at most 6.4; the degraded corridor (nothing along the road), median 8.3, its NDT up to 0.46 m off
  // along the road while its fitness stayed near 0.04 m^2.
  double max_degeneracy = 7.0;
};

enum class NdtHealth { kUnknown, kHealthy, kDegraded };

// The match itself failed: stopped at the iteration cap, or the scan does not fit the map there.
inline bool match_failed(const NdtQuality& q, const NdtQualityLimits& limits) {
  return (q.converged && !*q.converged) || (q.iterations && *q.iterations >= limits.max_iterations) ||
         (q.fitness_m2 && !(*q.fitness_m2 <= limits.max_fitness_m2));
}

// The match holds the vehicle too weakly in some direction.
inline bool too_degenerate(const NdtQuality& q, const NdtQualityLimits& limits) {
  return q.degeneracy && !(*q.degeneracy <= limits.max_degeneracy);
}

inline NdtHealth assess(const NdtQuality& q, const NdtQualityLimits& limits) {
  if (!q.converged && !q.iterations && !q.fitness_m2 && !q.degeneracy) {
    return NdtHealth::kUnknown;
  }
  return match_failed(q, limits) || too_degenerate(q, limits) ? NdtHealth::kDegraded : NdtHealth::kHealthy;
}

}  // namespace rsu::vehicle
