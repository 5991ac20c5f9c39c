// SPDX-License-Identifier: Apache-2.0
#include "perception/face_refinement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "common/symmetric_eigen.h"

namespace rsu::perception {
namespace {

struct Scatter {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
  std::size_t n = 0;
  void add(const Eigen::Vector2d& p) {
    sum += p;
    outer += p * p.transpose();
    ++n;
  }
  Eigen::Matrix2d centred() const {
    if (n == 0) {
      return Eigen::Matrix2d::Zero();
    }
    const Eigen::Vector2d mean = sum / static_cast<double>(n);
    return outer - static_cast<double>(n) * mean * mean.transpose();
  }
};

// The seen edge of `fit` whose face `r` (relative to `origin`) supports: within `d` of it and away from
// its corners; -1 for none.
int supported_edge(const RectangleFit& fit, const Eigen::Vector2d& origin, const Eigen::Vector2d& r, double d,
                   const FaceRefinementConfig& config) {
  int best_edge = -1;
  double best_dist = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    if (!fit.edges[uk].seen) {
      continue;
    }
    const Eigen::Vector2d a = fit.corners[uk] - origin;
    const Eigen::Vector2d b = fit.corners[(uk + 1) % 4] - origin;
    const double len = (b - a).norm();
    const Eigen::Vector2d t = (b - a) / len;
    const double s = (r - a).dot(t);
    const double excl = std::min(config.corner_exclusion_m, len / 4.0);
    const double dist = std::abs((r - a).dot(Eigen::Vector2d(t.y(), -t.x())));
    if (s >= excl && s <= len - excl && dist <= d && dist < best_dist) {
      best_dist = dist;
      best_edge = k;
    }
  }
  return best_edge;
}

// `fit` turned by `change` (its yaw kept in [0, pi/2): crossing it relabels the axes) and rebuilt around
// the finite `points`.
RectangleFit turned(const RectangleFit& fit, double change, std::span<const Eigen::Vector2d> points,
                    const Eigen::Vector2d& origin, const Eigen::Vector2d& lidar_xy,
                    const LShapeFitConfig& fit_config) {
  RectangleFit out = fit;
  double yaw = std::fmod(fit.yaw + change, std::numbers::pi / 2.0);
  if (yaw < 0.0) {
    yaw += std::numbers::pi / 2.0;
  }
  out.yaw = yaw;
  double c1_min = std::numeric_limits<double>::infinity(), c1_max = -c1_min;
  double c2_min = c1_min, c2_max = -c1_min;
  std::vector<Eigen::Vector2d> finite;
  finite.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) {
      continue;
    }
    finite.push_back(p);
    const Eigen::Vector2d r = p - origin;
    const double c1 = r.dot(out.axis0());
    const double c2 = r.dot(out.axis1());
    c1_min = std::min(c1_min, c1);
    c1_max = std::max(c1_max, c1);
    c2_min = std::min(c2_min, c2);
    c2_max = std::max(c2_max, c2);
  }
  set_rectangle_geometry(out, origin, c1_min, c1_max, c2_min, c2_max);
  set_edge_observations(out, finite, lidar_xy, fit_config);
  return out;
}

// The turn of the e1 direction (mod pi) that the least-squares lines of fit's seen faces give, or nothing
// when no face has enough points.
std::optional<double> face_turn(const RectangleFit& fit, std::span<const Eigen::Vector2d> points,
                                const LShapeFitConfig& fit_config, const FaceRefinementConfig& config) {
  // Work relative to the fit's centre (conditioning).
  const Eigen::Vector2d origin = fit.center;

  // Faces along e1 are edges 0 and 2; along e2, edges 1 and 3.
  Scatter along_e1;
  Scatter along_e2;
  for (const auto& p : points) {
    if (!p.allFinite()) {
      continue;
    }
    const Eigen::Vector2d r = p - origin;
    const int edge = supported_edge(fit, origin, r, fit_config.edge_support_m, config);
    if (edge == 0 || edge == 2) {
      along_e1.add(r);
    } else if (edge == 1 || edge == 3) {
      along_e2.add(r);
    }
  }
  const bool use1 = along_e1.n >= config.min_face_points;
  const bool use2 = along_e2.n >= config.min_face_points;
  if (!use1 && !use2) {
    return std::nullopt;
  }
  // n: the unit normal of the e1-faces (i.e. the e2 direction).
  const Eigen::Matrix2d m = (use1 ? along_e1.centred() : Eigen::Matrix2d::Zero()) -
                            (use2 ? along_e2.centred() : Eigen::Matrix2d::Zero());
  const SymmetricEigen2 eig(m);
  const Eigen::Vector2d n = eig.eigenvectors().col(0);
  const Eigen::Vector2d new_e1(n.y(), -n.x());
  // The eigenvector's sign is arbitrary.
  return std::remainder(std::atan2(new_e1.y(), new_e1.x()) - fit.yaw, std::numbers::pi);
}

}  // namespace

RectangleFit refine_on_faces(const RectangleFit& fit, std::span<const Eigen::Vector2d> points,
                             const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& fit_config,
                             const FaceRefinementConfig& config) {
  if (!fit.ok()) {
    return fit;
  }
  const std::optional<double> change = face_turn(fit, points, fit_config, config);
  if (!change || !(std::abs(*change) <= config.max_change_rad)) {
    return fit;
  }
  return turned(fit, *change, points, fit.center, lidar_xy, fit_config);
}

double refit_unsettled_rad(const RectangleFit& refined, std::span<const Eigen::Vector2d> points,
                           const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& fit_config,
                           const FaceRefinementConfig& config) {
  constexpr double kSettledRad = 1e-3;
  RectangleFit fit = refined;
  double total = 0.0, largest = 0.0;
  for (std::size_t pass = 0; pass < config.settle_passes && fit.ok(); ++pass) {
    const std::optional<double> turn = face_turn(fit, points, fit_config, config);
    if (!turn || !(std::abs(total + *turn) <= config.max_change_rad) || std::abs(*turn) < kSettledRad) {
      break;
    }
    fit = turned(fit, *turn, points, fit.center, lidar_xy, fit_config);
    total += *turn;
    largest = std::max(largest, std::abs(total));
  }
  return largest;
}

}  // namespace rsu::perception
