// SPDX-License-Identifier: Apache-2.0
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

// A criterion can be flat at its maximum (Autoware's closeness floors distances at 0.1 m, so every angle
// that keeps all points within 0.1 m of an edge scores the same: a plateau about +-0.1 m / face length
// wide). Picking the plateau's first angle biases the yaw by half its width; its middle is unbiased when
// the plateau is symmetric about the true direction. On an L of unequal faces it is not (the long face
// bounds one side, the short face the other): on a 4.5 x 1.8 m L it lands 0.25-0.55 deg off (measured on
// 2026-12-02; tests/perception/l_shape_criteria_test.cpp bounds it by the plateau, 1.27 deg).
// Returns the middle (in sample units, possibly x.5, possibly outside [0, n) when circular) of the run
// of samples equal to values[at].
double middle_of_tied_run(const std::vector<double>& values, std::size_t at, bool circular) {
  const auto n = static_cast<long>(values.size());
  const double top = values[at];
  auto value = [&](long i) { return values[static_cast<std::size_t>(circular ? ((i % n) + n) % n : i)]; };
  long lo = static_cast<long>(at);
  long hi = lo;
  while (hi - lo + 1 < n && (circular || lo > 0) && value(lo - 1) == top) {
    --lo;
  }
  while (hi - lo + 1 < n && (circular || hi < n - 1) && value(hi + 1) == top) {
    ++hi;
  }
  return 0.5 * static_cast<double>(lo + hi);
}

}  // namespace

OrientationResult search_exhaustive(CriterionEvaluator& criterion, double step_rad) {
  OrientationResult best;
  if (!(step_rad > 0.0) || !std::isfinite(step_rad)) {
    return best;
  }
  step_rad = std::min(std::max(step_rad, 1e-5), kQuarterTurn);
  const auto steps = static_cast<int>(std::ceil(kQuarterTurn / step_rad - 1e-9));
  std::vector<double> values(static_cast<std::size_t>(steps));
  std::size_t at = 0;
  for (int k = 0; k < steps; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    values[uk] = criterion(k * step_rad);
    if (values[uk] > values[at]) {
      at = uk;
    }
  }
  best.evaluations = values.size();
  best.value = values[at];
  // The grid is circular only when the step divides the quarter turn.
  const bool circular = std::abs(steps * step_rad - kQuarterTurn) < 1e-9;
  best.theta = wrap_quarter(middle_of_tied_run(values, at, circular) * step_rad);
  return best;
}

OrientationResult search_coarse_to_fine(CriterionEvaluator& criterion,
                                        const OrientationSearchConfig& config) {
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
  std::sort(peaks.begin(), peaks.end(),
            [&](int a, int b) { return q[static_cast<std::size_t>(a)] > q[static_cast<std::size_t>(b)]; });
  peaks.resize(
      std::min<std::size_t>(peaks.size(), static_cast<std::size_t>(std::max(1, config.coarse_peaks))));

  OrientationResult best;
  best.value = -std::numeric_limits<double>::infinity();
  auto consider = [&](double theta) {
    const double t = wrap_quarter(theta);
    const double v = criterion(t);
    if (v > best.value) {
      best.value = v;
      best.theta = t;
    }
  };
  // Dense scan of +-window around each coarse peak, on the global grid of `dense` steps; the best
  // sample, moved to the middle of its plateau if it has one.
  const double dense = deg_to_rad(std::clamp(config.dense_step_deg, 1e-3, config.coarse_step_deg));
  const double window = deg_to_rad(std::max(0.0, config.dense_window_deg));
  for (const int k : peaks) {
    const double centre = k * step;
    const auto first = static_cast<long>(std::ceil((centre - window) / dense - 1e-9));
    const auto last = static_cast<long>(std::floor((centre + window) / dense + 1e-9));
    std::vector<double> values;
    std::size_t at = 0;
    for (long j = first; j <= last; ++j) {
      values.push_back(criterion(wrap_quarter(static_cast<double>(j) * dense)));
      if (values.back() > values[at]) {
        at = values.size() - 1;
      }
    }
    if (!values.empty() && values[at] > best.value) {
      best.value = values[at];
      best.theta = wrap_quarter((static_cast<double>(first) + middle_of_tied_run(values, at, false)) * dense);
    }
  }
  // Then successively finer grids around the best, each spanning +-1 step of the previous.
  for (double sub = dense / 5.0, half = dense; half > fine * 1.0001;
       half = sub, sub = std::max(sub / 5.0, fine)) {
    const double centre = best.theta;
    const auto m = static_cast<int>(std::round(half / sub));
    for (int j = -m; j <= m; ++j) {
      if (j != 0) {
        consider(centre + j * sub);
      }
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
