// SPDX-License-Identifier: Apache-2.0
#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "common/angles.h"

namespace rsu::sim {
namespace {

bool finite(const Pose2& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw);
}

// Index of the first waypoint strictly after t (points are sorted by time).
std::size_t first_after(const Waypoints& w, TimeNs t) {
  const auto it = std::upper_bound(w.points.begin(), w.points.end(), t,
                                   [](TimeNs value, const TimedPose& p) { return value < p.t; });
  return static_cast<std::size_t>(it - w.points.begin());
}

// Position and velocity of the smooth path at t, inside segment [a, b] = points[next - 1], points[next].
struct PathState {
  Eigen::Vector2d position;
  Eigen::Vector2d velocity;  // m/s
};

// Tangent at point i by central differences in time (one-sided at the ends), m/s.
Eigen::Vector2d tangent(const Waypoints& w, std::size_t i) {
  const std::size_t lo = i == 0 ? 0 : i - 1;
  const std::size_t hi = i + 1 == w.points.size() ? i : i + 1;
  const TimedPose& a = w.points[lo];
  const TimedPose& b = w.points[hi];
  return Eigen::Vector2d(b.pose.x - a.pose.x, b.pose.y - a.pose.y) / to_seconds(b.t - a.t);
}

PathState hermite(const Waypoints& w, std::size_t next, TimeNs t) {
  const TimedPose& a = w.points[next - 1];
  const TimedPose& b = w.points[next];
  const double h = to_seconds(b.t - a.t);
  const double s = static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t);
  const Eigen::Vector2d p0(a.pose.x, a.pose.y), p1(b.pose.x, b.pose.y);
  const Eigen::Vector2d m0 = tangent(w, next - 1) * h, m1 = tangent(w, next) * h;
  const double s2 = s * s, s3 = s2 * s;
  PathState out;
  out.position =
      (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1;
  out.velocity =
      ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * m1) /
      h;
  return out;
}

// Below this speed the direction of motion is meaningless and the points' yaw is used.
constexpr double kStandingStillMps = 0.05;

Pose2 linear_pose(const TimedPose& a, const TimedPose& b, TimeNs t) {
  // Integer numerator and denominator first: exact for any time span before the one division.
  const double s = static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t);
  return {a.pose.x + s * (b.pose.x - a.pose.x), a.pose.y + s * (b.pose.y - a.pose.y),
          wrap_angle(a.pose.yaw + s * wrap_angle(b.pose.yaw - a.pose.yaw))};
}

Pose2 waypoint_pose(const Waypoints& w, TimeNs t) {
  if (w.points.empty()) {
    throw std::invalid_argument("trajectory: Waypoints has no points");
  }
  const std::size_t next = first_after(w, t);
  if (next == 0) {
    return w.points.front().pose;  // held before the first point
  }
  if (next == w.points.size()) {
    return w.points.back().pose;  // held after the last point
  }
  const Pose2 linear = linear_pose(w.points[next - 1], w.points[next], t);
  if (!w.smooth) {
    return linear;
  }
  const PathState path = hermite(w, next, t);
  const double yaw = path.velocity.norm() > kStandingStillMps
                         ? std::atan2(path.velocity.y(), path.velocity.x())
                         : linear.yaw;
  return {path.position.x(), path.position.y(), yaw};
}

Velocity2 waypoint_velocity(const Waypoints& w, TimeNs t) {
  if (w.points.empty()) {
    throw std::invalid_argument("trajectory: Waypoints has no points");
  }
  const std::size_t next = first_after(w, t);
  if (next == 0 || next == w.points.size()) {
    return {};
  }
  const TimedPose& a = w.points[next - 1];
  const TimedPose& b = w.points[next];
  if (!w.smooth) {
    const double dt = to_seconds(b.t - a.t);
    return {(b.pose.x - a.pose.x) / dt, (b.pose.y - a.pose.y) / dt, wrap_angle(b.pose.yaw - a.pose.yaw) / dt};
  }
  // Yaw rate of the direction of motion, by a central difference over 1 ms (well inside the segment's
  // smooth cubic; clamped to the segment).
  const PathState path = hermite(w, next, t);
  const TimeNs dt = kNsPerMs;
  const TimeNs t0 = std::max(a.t, t - dt), t1 = std::min(b.t, t + dt);
  const double yaw_rate =
      t1 > t0 ? wrap_angle(waypoint_pose(w, t1).yaw - waypoint_pose(w, t0).yaw) / to_seconds(t1 - t0) : 0.0;
  return {path.velocity.x(), path.velocity.y(), yaw_rate};
}

}  // namespace

Pose2 pose_at(const Trajectory& trajectory, TimeNs t) {
  return std::visit(
      [t](const auto& tr) -> Pose2 {
        using T = std::decay_t<decltype(tr)>;
        if constexpr (std::is_same_v<T, StaticPose>) {
          return {tr.pose.x, tr.pose.y, wrap_angle(tr.pose.yaw)};
        } else if constexpr (std::is_same_v<T, Spin>) {
          return {tr.x, tr.y, wrap_angle(tr.yaw0 + tr.rate_rad_s * to_seconds(t - tr.t0))};
        } else {
          return waypoint_pose(tr, t);
        }
      },
      trajectory);
}

Velocity2 velocity_at(const Trajectory& trajectory, TimeNs t) {
  return std::visit(
      [t](const auto& tr) -> Velocity2 {
        using T = std::decay_t<decltype(tr)>;
        if constexpr (std::is_same_v<T, StaticPose>) {
          return {};
        } else if constexpr (std::is_same_v<T, Spin>) {
          return {0.0, 0.0, tr.rate_rad_s};
        } else {
          return waypoint_velocity(tr, t);
        }
      },
      trajectory);
}

std::vector<Eigen::Vector2d> path_vertices(const Trajectory& trajectory, TimeNs t0, TimeNs t1) {
  std::vector<Eigen::Vector2d> points;
  const Pose2 start = pose_at(trajectory, t0);
  const Pose2 end = pose_at(trajectory, t1);
  points.emplace_back(start.x, start.y);
  if (const auto* w = std::get_if<Waypoints>(&trajectory)) {
    if (w->smooth) {
      // A curve can leave the chords between its points: sample it every 5 ms as well.
      for (TimeNs t = t0 + 5 * kNsPerMs; t < t1; t += 5 * kNsPerMs) {
        const Pose2 p = pose_at(trajectory, t);
        points.emplace_back(p.x, p.y);
      }
    } else {
      for (std::size_t i = first_after(*w, t0); i < w->points.size() && w->points[i].t < t1; ++i) {
        points.emplace_back(w->points[i].pose.x, w->points[i].pose.y);
      }
    }
  }
  points.emplace_back(end.x, end.y);
  return points;
}

void validate_trajectory(const Trajectory& trajectory) {
  std::visit(
      [](const auto& tr) {
        using T = std::decay_t<decltype(tr)>;
        if constexpr (std::is_same_v<T, StaticPose>) {
          if (!finite(tr.pose)) {
            throw std::invalid_argument("trajectory: StaticPose has a non-finite pose");
          }
        } else if constexpr (std::is_same_v<T, Spin>) {
          if (!std::isfinite(tr.x) || !std::isfinite(tr.y) || !std::isfinite(tr.yaw0) ||
              !std::isfinite(tr.rate_rad_s)) {
            throw std::invalid_argument("trajectory: Spin has a non-finite centre, yaw or rate");
          }
        } else {
          if (tr.points.empty()) {
            throw std::invalid_argument("trajectory: Waypoints has no points");
          }
          for (std::size_t i = 0; i < tr.points.size(); ++i) {
            if (!finite(tr.points[i].pose)) {
              throw std::invalid_argument("trajectory: waypoint " + std::to_string(i) +
                                          " has a non-finite pose");
            }
            if (i > 0 && tr.points[i].t < tr.points[i - 1].t) {
              throw std::invalid_argument("trajectory: waypoint " + std::to_string(i) +
                                          " is earlier than the one before");
            }
          }
        }
      },
      trajectory);
}

}  // namespace rsu::sim
