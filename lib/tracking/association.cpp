// SPDX-License-Identifier: Apache-2.0
#include "tracking/association.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <Eigen/Geometry>

#include "common/angles.h"

#include "tracking/assignment.h"

namespace rsu::tracking {
namespace {

bool is_finite(const perception::RectangleFit& c) {
  return c.ok() && c.center.allFinite() && std::isfinite(c.yaw) && std::isfinite(c.length0) &&
         std::isfinite(c.length1) && c.length0 >= 0.0 && c.length1 >= 0.0;
}

bool is_finite(const VehicleHypothesis& v) {
  return v.centre.allFinite() && std::isfinite(v.yaw) && v.covariance.allFinite() &&
         std::isfinite(v.size.length_m) && std::isfinite(v.size.width_m);
}

// How far the fitted centre may sit from the true one along each box axis because of unseen extent:
// half the announced dimension missing from the fitted edge, along the box axes at `axis_yaw`. With
// the vehicle's heading known (AssociationConfig::pairing_max_yaw_sigma_rad) the fitted edge nearer
// it is along the length and the spread lies along the heading (a small cluster's own fitted yaw is
// arbitrary and would point its half-length spread anywhere). Otherwise which announced dimension
// lies along which fitted edge is unknown (the off-by-90 deg problem): every pairing the edge lengths
// allow is taken and the larger spread kept per axis of the fitted box.
struct UnseenSpread {
  Eigen::Vector2d half = Eigen::Vector2d::Zero();
  double axis_yaw = 0.0;
};

UnseenSpread unseen_half_extent(const perception::RectangleFit& c, const VehicleHypothesis& v,
                                const AssociationConfig& cfg) {
  const v2i::BoxSize& size = v.size;
  const double slack_long = size.length_m * cfg.size_relative_tolerance + cfg.size_absolute_tolerance_m;
  const double slack_wide = size.width_m * cfg.size_relative_tolerance + cfg.size_absolute_tolerance_m;
  // With the heading known (AssociationConfig::pairing_max_yaw_sigma_rad), only the pairing it gives.
  bool allow_along_is_length = true;
  bool allow_along_is_width = true;
  double axis_yaw = c.yaw;
  const double yaw_var = v.covariance(2, 2);
  if (yaw_var >= 0.0 && std::sqrt(yaw_var) < cfg.pairing_max_yaw_sigma_rad) {
    const double off = std::abs(std::remainder(c.yaw - v.yaw, kPi));  // in [0, pi/2]
    allow_along_is_length = off < kPi / 4.0;
    allow_along_is_width = !allow_along_is_length;
    // The spread's axes are the heading's; "along" the fitted box is along the heading or across it.
    axis_yaw = allow_along_is_length ? v.yaw : v.yaw + kPi / 2.0;
  }
  Eigen::Vector2d spread = Eigen::Vector2d::Zero();
  bool any = false;
  // Pairing 1: along <-> length, across <-> width. Pairing 2: along <-> width, across <-> length.
  if (allow_along_is_length && c.length0 <= size.length_m + slack_long &&
      c.length1 <= size.width_m + slack_wide) {
    spread = spread.cwiseMax(
        Eigen::Vector2d(std::max(0.0, size.length_m - c.length0), std::max(0.0, size.width_m - c.length1)));
    any = true;
  }
  if (allow_along_is_width && c.length0 <= size.width_m + slack_wide &&
      c.length1 <= size.length_m + slack_long) {
    spread = spread.cwiseMax(
        Eigen::Vector2d(std::max(0.0, size.width_m - c.length0), std::max(0.0, size.length_m - c.length1)));
    any = true;
  }
  return {any ? Eigen::Vector2d(0.5 * spread) : Eigen::Vector2d::Zero(), axis_yaw};
}

// d^T S^-1 d with the closed-form 2x2 inverse; empty when S is not positive definite.
std::optional<double> mahalanobis_sq(const Eigen::Vector2d& d, const Eigen::Matrix2d& s) {
  const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
  if (!(det > 0.0) || !(s(0, 0) > 0.0))
    return std::nullopt;
  return (s(1, 1) * d.x() * d.x() - (s(0, 1) + s(1, 0)) * d.x() * d.y() + s(0, 0) * d.y() * d.y()) / det;
}

// The part of the centre offset `d` beyond the unseen-extent bound along each of its axes (map frame).
Eigen::Vector2d offset_beyond_bound(const Eigen::Vector2d& d, const UnseenSpread& spread) {
  const Eigen::Rotation2Dd to_axes(-spread.axis_yaw);
  const Eigen::Vector2d along = to_axes * d;
  Eigen::Vector2d beyond;
  for (int i = 0; i < 2; ++i)
    beyond[i] = std::copysign(std::max(0.0, std::abs(along[i]) - spread.half[i]), along[i]);
  return to_axes.inverse() * beyond;
}

bool size_consistent(const perception::RectangleFit& c, const v2i::BoxSize& size,
                     const AssociationConfig& cfg) {
  const double longer = std::max(c.length0, c.length1);
  const double shorter = std::min(c.length0, c.length1);
  return longer <= size.length_m * (1.0 + cfg.size_relative_tolerance) + cfg.size_absolute_tolerance_m &&
         shorter <= size.width_m * (1.0 + cfg.size_relative_tolerance) + cfg.size_absolute_tolerance_m;
}

}  // namespace

PairCheck check_pair(const perception::RectangleFit& cluster, const VehicleHypothesis& vehicle,
                     const AssociationConfig& config) {
  PairCheck out;
  if (!is_finite(cluster) || !is_finite(vehicle)) {
    return out;  // kInvalid
  }
  if (!size_consistent(cluster, vehicle.size, config)) {
    out.verdict = PairGate::kSizeMismatch;
    return out;
  }
  Eigen::Matrix2d noise = vehicle.covariance.topLeftCorner<2, 2>();
  noise += config.fit_sigma_floor_m * config.fit_sigma_floor_m * Eigen::Matrix2d::Identity();
  Eigen::Matrix2d s = noise;
  std::optional<UnseenSpread> spread;
  if (config.inflate_for_unseen_extent) {
    spread = unseen_half_extent(cluster, vehicle, config);
    const Eigen::Matrix2d axes = Eigen::Rotation2Dd(spread->axis_yaw).toRotationMatrix();
    s += axes * spread->half.cwiseProduct(spread->half).asDiagonal() * axes.transpose();
  }
  const Eigen::Vector2d d = cluster.center - vehicle.centre;
  const std::optional<double> distance_sq = mahalanobis_sq(d, s);
  if (!distance_sq)
    return out;  // kInvalid: the vehicle's covariance is not positive semi-definite
  out.distance_sq = *distance_sq;
  out.verdict = out.distance_sq <= config.gate_chi2 ? PairGate::kPass : PairGate::kTooFar;
  // The spread above is a bound, not a noise: a part of the vehicle lies INSIDE its footprint, so its
  // fitted centre sits at most half the unseen extent from the vehicle's (per axis), never beyond.
  // Spread as a variance it lets a small cluster pass up to three times that far: a neighbour's
  // bonnet or a van's sill a whole car length outside the footprint, seen from 4-6 m up, joined a
  // car and pulled its fix 2 m (README, "An elevated RSU"). So a cluster must also lie within the
  // gate of the footprint itself: the offset beyond the bound, against the vehicle's and the fit's
  // own noise.
  if (out.verdict == PairGate::kPass && spread) {
    const Eigen::Vector2d beyond = offset_beyond_bound(d, *spread);
    const std::optional<double> beyond_sq = mahalanobis_sq(beyond, noise);
    if (!beyond_sq || *beyond_sq > config.gate_chi2)
      out.verdict = PairGate::kTooFar;
  }
  return out;
}

namespace {

// Rows: the vehicles with at least one cluster inside their gate (`gated`, vehicle indices in order;
// `distance` holds their passing pairs, -1 elsewhere). Columns: clusters, then one private "no cluster"
// column per such vehicle costing the gate value. A forbidden pairing costs more than leaving every
// vehicle unmatched, so the optimum never uses one while staying finite (the solver's potentials stay
// well conditioned). A vehicle with no cluster in its gate has nothing but its own "no cluster" column
// below the forbidden cost, so every optimum leaves it unmatched and no other vehicle takes that column:
// it is left out (1000 registered vehicles, a handful in view: the full matrix was 1000 x 1004 per batch,
// 17 % of rsud's time under the signed load). The forbidden cost stays that of the full matrix.
void assign_gated(const Eigen::MatrixXd& distance, std::span<const Eigen::Index> gated,
                  std::span<const std::size_t> offered, const AssociationConfig& config,
                  AssociationResult& result) {
  const double unmatched_cost = config.gate_chi2;
  const double forbidden = unmatched_cost * static_cast<double>(distance.rows() + 1) + 1.0;
  const auto n_clusters = static_cast<Eigen::Index>(offered.size());
  const auto n_rows = static_cast<Eigen::Index>(gated.size());
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(n_rows, n_clusters + n_rows, forbidden);
  for (Eigen::Index r = 0; r < n_rows; ++r) {
    cost(r, n_clusters + r) = unmatched_cost;
    for (Eigen::Index c = 0; c < n_clusters; ++c) {
      if (distance(gated[static_cast<std::size_t>(r)], c) >= 0.0)
        cost(r, c) = distance(gated[static_cast<std::size_t>(r)], c);
    }
  }
  const std::optional<Assignment> assignment = solve_assignment(cost);
  if (!assignment)
    return;
  for (Eigen::Index r = 0; r < n_rows; ++r) {
    const int c = assignment->row_to_col[static_cast<std::size_t>(r)];
    if (c >= 0 && c < n_clusters && cost(r, c) < forbidden) {
      result.pairs.push_back({offered[static_cast<std::size_t>(c)],
                              static_cast<std::size_t>(gated[static_cast<std::size_t>(r)]), cost(r, c)});
    }
  }
}

}  // namespace

AssociationResult associate(std::span<const perception::Detection> detections,
                            std::span<const VehicleHypothesis> vehicles, const AssociationConfig& config) {
  // Only detections with a rectangle are offered: the assignment runs over them (columns in order).
  std::vector<std::size_t> offered;
  for (std::size_t d = 0; d < detections.size(); ++d) {
    if (detections[d].fit.ok())
      offered.push_back(d);
  }
  AssociationResult result;
  const auto n_clusters = static_cast<Eigen::Index>(offered.size());
  const auto n_vehicles = static_cast<Eigen::Index>(vehicles.size());
  Eigen::MatrixXd distance = Eigen::MatrixXd::Constant(n_vehicles, n_clusters, -1.0);  // -1: not passed
  std::vector<Eigen::Index> gated;  // vehicles with a cluster in their gate, in order
  for (Eigen::Index v = 0; v < n_vehicles; ++v) {
    bool any_pass = false;
    for (Eigen::Index c = 0; c < n_clusters; ++c) {
      const PairCheck check = check_pair(detections[offered[static_cast<std::size_t>(c)]].fit,
                                         vehicles[static_cast<std::size_t>(v)], config);
      switch (check.verdict) {
        case PairGate::kPass:
          distance(v, c) = check.distance_sq;
          any_pass = true;
          break;
        case PairGate::kTooFar:
          ++result.pairs_too_far;
          break;
        case PairGate::kSizeMismatch:
          ++result.pairs_size_mismatch;
          break;
        case PairGate::kInvalid:
          ++result.pairs_invalid;
          break;
      }
    }
    if (any_pass)
      gated.push_back(v);
  }
  if (!gated.empty())
    assign_gated(distance, gated, offered, config, result);

  std::vector<char> cluster_used(detections.size(), 0);
  std::vector<char> vehicle_used(vehicles.size(), 0);
  for (const AssociatedPair& p : result.pairs) {
    cluster_used[p.cluster] = 1;
    vehicle_used[p.vehicle] = 1;
  }
  std::sort(result.pairs.begin(), result.pairs.end(),
            [](const AssociatedPair& a, const AssociatedPair& b) { return a.cluster < b.cluster; });
  for (std::size_t c = 0; c < detections.size(); ++c) {
    if (!cluster_used[c]) {
      result.unmatched_clusters.push_back(c);
    }
  }
  for (std::size_t v = 0; v < vehicles.size(); ++v) {
    if (!vehicle_used[v]) {
      result.unmatched_vehicles.push_back(v);
    }
  }
  return result;
}

}  // namespace rsu::tracking
