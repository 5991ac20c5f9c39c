// Searches theta in [0, 90 deg) for the maximum of an L-shape criterion (Zhang et al. 2017, Alg. 2).
//
//  - exhaustive: every step (1 deg as in Zhang and Autoware), the reference.
//  - coarse_to_fine: a coarse grid (2 deg), then the best few local maxima of it (the criteria are
//    multimodal: an L has a second, weaker mode near its diagonal) are each refined by successively
//    finer grids around the current best (+-1 coarse step at step/4, then +-1 of that at /5, ...) down to
//    `fine_resolution_deg`. About 45 + 3 * 30 evaluations to reach 0.02 deg, where an exhaustive search
//    at 0.1 deg needs 900. The criterion near its optimum rises monotonically towards it at the coarse
//    scale (each point's edge distance shrinks with |theta - theta*|), which is what makes refinement
//    around the coarse maxima find the global one; the property test checks it on random clusters.
#pragma once

#include <cstddef>

#include "perception/l_shape_criteria.h"

namespace rsu::perception {

enum class OrientationSearchMethod { exhaustive, coarse_to_fine };

struct OrientationSearchConfig {
  OrientationSearchMethod method = OrientationSearchMethod::coarse_to_fine;
  double exhaustive_step_deg = 1.0;
  double coarse_step_deg = 2.0;
  int coarse_peaks = 3;
  double fine_resolution_deg = 0.02;
};

struct OrientationResult {
  double theta = 0.0;  // radians, [0, pi/2)
  double value = 0.0;  // criterion at theta
  std::size_t evaluations = 0;
};

// step_rad must be > 0; theta = 0, step, 2 step, ... < pi/2. Ties keep the first (smallest theta).
OrientationResult search_exhaustive(CriterionEvaluator& criterion, double step_rad);
OrientationResult search_coarse_to_fine(CriterionEvaluator& criterion, const OrientationSearchConfig& config);
OrientationResult search_orientation(CriterionEvaluator& criterion, const OrientationSearchConfig& config);

}  // namespace rsu::perception
