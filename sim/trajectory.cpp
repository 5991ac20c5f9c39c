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
  const TimedPose& a = w.points[next - 1];
  const TimedPose& b = w.points[next];
  // Integer numerator and denominator first: exact for any time span before the one division.
  const double s = static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t);
  return {a.pose.x + s * (b.pose.x - a.pose.x), a.pose.y + s * (b.pose.y - a.pose.y),
          wrap_angle(a.pose.yaw + s * wrap_angle(b.pose.yaw - a.pose.yaw))};
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
  const double dt = to_seconds(b.t - a.t);
  return {(b.pose.x - a.pose.x) / dt, (b.pose.y - a.pose.y) / dt, wrap_angle(b.pose.yaw - a.pose.yaw) / dt};
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
    for (std::size_t i = first_after(*w, t0); i < w->points.size() && w->points[i].t < t1; ++i) {
      points.emplace_back(w->points[i].pose.x, w->points[i].pose.y);
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
