#include "perception/orientation_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "common/angles.h"

namespace rsu::perception {
namespace {

constexpr double kQuarterTurn = std::numbers::pi / 2.0;

// Criterion period is pi/2: map any angle into [0, pi/2).
double wrap_quarter(double theta) {
  double t = std::fmod(theta, kQuarterTurn);
  if (t < 0.0) {
    t += kQuarterTurn;
  }
  return t >= kQuarterTurn ? 0.0 : t;
}

}  // namespace

OrientationResult search_exhaustive(CriterionEvaluator& criterion, double step_rad) {
  OrientationResult best;
  if (!(step_rad > 0.0)) {
    return best;
  }
  const auto steps = static_cast<int>(std::ceil(kQuarterTurn / step_rad - 1e-9));
  bool first = true;
  for (int k = 0; k < steps; ++k) {
    const double theta = k * step_rad;
    const double q = criterion(theta);
    ++best.evaluations;
    if (first || q > best.value) {
      best.theta = theta;
      best.value = q;
      first = false;
    }
  }
  return best;
}

OrientationResult search_coarse_to_fine(CriterionEvaluator& criterion, const OrientationSearchConfig& config) {
  const std::size_t evaluations_before = criterion.evaluations();
  const double coarse = deg_to_rad(std::clamp(config.coarse_step_deg, 0.1, 30.0));
  const double fine = deg_to_rad(std::clamp(config.fine_resolution_deg, 1e-4, config.coarse_step_deg));
  const auto n = static_cast<int>(std::ceil(kQuarterTurn / coarse - 1e-9));
  const double step = kQuarterTurn / n;  // whole steps around the circle of period pi/2
  std::vector<double> q(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    q[static_cast<std::size_t>(k)] = criterion(k * step);
  }

  // Local maxima of the periodic coarse grid (plateaus: the first sample of the plateau), best first.
  std::vector<int> peaks;
  for (int k = 0; k < n; ++k) {
    const double here = q[static_cast<std::size_t>(k)];
    const double prev = q[static_cast<std::size_t>((k + n - 1) % n)];
    const double next = q[static_cast<std::size_t>((k + 1) % n)];
    if (here > prev && here >= next) {
      peaks.push_back(k);
    }
  }
  if (peaks.empty()) {  // constant criterion
    peaks.push_back(0);
  }
  std::sort(peaks.begin(), peaks.end(), [&](int a, int b) {
    return q[static_cast<std::size_t>(a)] > q[static_cast<std::size_t>(b)];
  });
  peaks.resize(std::min<std::size_t>(peaks.size(), static_cast<std::size_t>(std::max(1, config.coarse_peaks))));

  OrientationResult best;
  best.value = -std::numeric_limits<double>::infinity();
  for (const int k : peaks) {
    double centre = k * step;
    double centre_q = q[static_cast<std::size_t>(k)];
    double half = step;         // search [centre - half, centre + half]
    double sub = step / 4.0;    // at this spacing
    while (true) {
      const auto m = static_cast<int>(std::round(half / sub));
      const double from = centre;
      for (int j = -m; j <= m; ++j) {
        if (j == 0) {
          continue;
        }
        const double theta = from + j * sub;
        const double v = criterion(wrap_quarter(theta));
        if (v > centre_q) {
          centre_q = v;
          centre = theta;
        }
      }
      if (sub <= fine * 1.0001) {
        break;
      }
      half = sub;
      sub = std::max(sub / 5.0, fine);
    }
    if (centre_q > best.value) {
      best.value = centre_q;
      best.theta = wrap_quarter(centre);
    }
  }
  best.evaluations = criterion.evaluations() - evaluations_before;
  return best;
}

OrientationResult search_orientation(CriterionEvaluator& criterion, const OrientationSearchConfig& config) {
  if (config.method == OrientationSearchMethod::exhaustive) {
    return search_exhaustive(criterion, deg_to_rad(config.exhaustive_step_deg));
  }
  return search_coarse_to_fine(criterion, config);
}

}  // namespace rsu::perception
