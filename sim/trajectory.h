// SPDX-License-Identifier: Apache-2.0
// Vehicle trajectories (sim/scene.h) evaluated at a time: pose and velocity of the footprint centre.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/pose.h"
#include "common/time.h"
#include "sim/scene.h"

namespace rsu::sim {

// Planar velocity in the map frame.
struct Velocity2 {
  double vx = 0.0;        // m/s
  double vy = 0.0;        // m/s
  double yaw_rate = 0.0;  // rad/s, counter-clockwise positive
};

// Pose at time t; yaw wrapped to (-pi, pi].
//   StaticPose: constant.
//   Spin:       position fixed, yaw = yaw0 + rate * (t - t0).
//   Waypoints:  linear in x, y and in yaw along the shorter way round between consecutive points;
//               held before the first and after the last point. Two points at the same time make a
//               jump (the later one wins from that time on).
// Throws std::invalid_argument for an invalid trajectory (see validate_trajectory).
Pose2 pose_at(const Trajectory& trajectory, TimeNs t);

// Velocity at time t (zero while a Waypoints trajectory is held; the segment after t at a waypoint).
Velocity2 velocity_at(const Trajectory& trajectory, TimeNs t);

// Footprint-centre positions at t0, at t1 and at every waypoint strictly between. Positions are
// piecewise linear in time, so the path over [t0, t1] (t0 <= t1) lies in the convex hull of these
// points: the ray caster bounds a moving vehicle over a batch of rays with them.
std::vector<Eigen::Vector2d> path_vertices(const Trajectory& trajectory, TimeNs t0, TimeNs t1);

// Throws std::invalid_argument with a clear message for: non-finite numbers, an empty Waypoints
// list, or waypoint times that decrease.
void validate_trajectory(const Trajectory& trajectory);

}  // namespace rsu::sim
