// SPDX-License-Identifier: Apache-2.0
#include "perception/l_shape_fitting.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "common/symmetric_eigen.h"

namespace rsu::perception {
namespace {

struct Extent {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void add(double v) {
    min = std::min(min, v);
    max = std::max(max, v);
  }
  double size() const { return max - min; }
};

// Spread of the (centred) points along and across their principal axis: a line or a spot has no
// rectangle, whatever angle a criterion would pick.
bool is_degenerate(const std::vector<double>& x, const std::vector<double>& y, double min_extent) {
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector2d p(x[i], y[i]);
    scatter += p * p.transpose();
  }
  const SymmetricEigen2 eig(scatter);
  const Eigen::Vector2d minor = eig.eigenvectors().col(0);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  Extent across;
  Extent along;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector2d p(x[i], y[i]);
    across.add(p.dot(minor));
    along.add(p.dot(major));
  }
  return !(along.size() >= min_extent) || !(across.size() >= min_extent);
}

}  // namespace

std::string_view to_string(FitStatus status) {
  switch (status) {
    case FitStatus::ok:
      return "ok";
    case FitStatus::too_few_points:
      return "too_few_points";
    case FitStatus::non_finite_points:
      return "non_finite_points";
    case FitStatus::degenerate:
      return "degenerate";
  }
  return "unknown";
}

Eigen::Vector2d RectangleFit::axis0() const {
  return {std::cos(yaw), std::sin(yaw)};
}
Eigen::Vector2d RectangleFit::axis1() const {
  return {-std::sin(yaw), std::cos(yaw)};
}

void set_rectangle_geometry(RectangleFit& fit, const Eigen::Vector2d& origin, double c1_min, double c1_max,
                            double c2_min, double c2_max) {
  const Eigen::Vector2d e1 = fit.axis0();
  const Eigen::Vector2d e2 = fit.axis1();
  fit.length0 = c1_max - c1_min;
  fit.length1 = c2_max - c2_min;
  fit.corners[0] = origin + c1_min * e1 + c2_min * e2;
  fit.corners[1] = origin + c1_max * e1 + c2_min * e2;
  fit.corners[2] = origin + c1_max * e1 + c2_max * e2;
  fit.corners[3] = origin + c1_min * e1 + c2_max * e2;
  fit.center = origin + 0.5 * (c1_min + c1_max) * e1 + 0.5 * (c2_min + c2_max) * e2;
}

void set_edge_observations(RectangleFit& fit, std::span<const Eigen::Vector2d> points,
                           const Eigen::Vector2d& lidar_xy, const LShapeFitConfig& config) {
  const double d = config.edge_support_m;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d& a = fit.corners[static_cast<std::size_t>(k)];
    const Eigen::Vector2d& b = fit.corners[static_cast<std::size_t>((k + 1) % 4)];
    const double len = (b - a).norm();
    RectangleEdge& edge = fit.edges[static_cast<std::size_t>(k)];
    edge = RectangleEdge{};
    if (!(len > 0.0)) {
      continue;
    }
    const Eigen::Vector2d t = (b - a) / len;
    const Eigen::Vector2d outward(t.y(), -t.x());  // corners are counter-clockwise
    for (const auto& p : points) {
      const Eigen::Vector2d r = p - a;
      const double s = r.dot(t);
      if (s >= -d && s <= len + d && std::abs(r.dot(outward)) <= d) {
        ++edge.support_points;
      }
    }
    edge.faces_lidar = (lidar_xy - 0.5 * (a + b)).dot(outward) > 0.0;
    edge.seen =
        edge.faces_lidar && len >= config.min_face_length_m && edge.support_points >= config.min_face_points;
  }
}

RectangleFit fit_rectangle(std::span<const Eigen::Vector2d> points, const Eigen::Vector2d& lidar_xy,
                           const LShapeFitConfig& config) {
  RectangleFit fit;
  std::vector<Eigen::Vector2d> finite;
  finite.reserve(points.size());
  for (const auto& p : points) {
    if (std::isfinite(p.x()) && std::isfinite(p.y())) {
      finite.push_back(p);
    }
  }
  fit.non_finite_dropped = points.size() - finite.size();
  fit.points_used = finite.size();
  const std::size_t min_points = std::max<std::size_t>(config.min_points, 3);
  if (finite.size() < min_points) {
    fit.status = points.size() >= min_points ? FitStatus::non_finite_points : FitStatus::too_few_points;
    return fit;
  }

  // Work relative to the centroid: map coordinates are hundreds of metres, the cluster a few.
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  for (const auto& p : finite) {
    origin += p;
  }
  origin /= static_cast<double>(finite.size());
  std::vector<double> x(finite.size());
  std::vector<double> y(finite.size());
  for (std::size_t i = 0; i < finite.size(); ++i) {
    x[i] = finite[i].x() - origin.x();
    y[i] = finite[i].y() - origin.y();
  }
  if (is_degenerate(x, y, config.min_extent_m)) {
    fit.status = FitStatus::degenerate;
    return fit;
  }

  CriterionEvaluator criterion(x, y, config.criterion);
  const OrientationResult best = search_orientation(criterion, config.search);
  fit.yaw = best.theta;
  fit.criterion_value = best.value;

  const Eigen::Vector2d e1 = fit.axis0();
  const Eigen::Vector2d e2 = fit.axis1();
  Extent c1;
  Extent c2;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector2d p(x[i], y[i]);
    c1.add(p.dot(e1));
    c2.add(p.dot(e2));
  }
  set_rectangle_geometry(fit, origin, c1.min, c1.max, c2.min, c2.max);
  if (!(std::min(fit.length0, fit.length1) >= config.min_extent_m)) {
    fit.status = FitStatus::degenerate;
    return fit;
  }
  set_edge_observations(fit, finite, lidar_xy, config);
  fit.status = FitStatus::ok;
  return fit;
}

}  // namespace rsu::perception
