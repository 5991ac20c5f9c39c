// SPDX-License-Identifier: Apache-2.0
// A scene as plain data: what is where. Scenario files (sim/scenario.h) are parsed into it; the ray
// caster (sim/raycaster.h) builds meshes from it. Map frame: ENU, metres, radians (docs/design.md §3).
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "common/pose.h"
#include "common/time.h"

namespace rsu::sim {

// Lambertian reflectivity in [0, 1] per surface class; the simulated intensity is
// 255 * reflectivity * |cos(incidence)|.
struct Reflectivity {
  double ground = 0.15;
  double building = 0.35;
  double pole = 0.5;
  double vegetation = 0.25;
  double vehicle = 0.6;
};

struct Ground {
  double half_extent_m = 250.0;  // a square of side 2 * half_extent centred at the origin, at z = 0
};

// An axis-aligned-in-its-own-frame box standing on the ground: centre (x, y), rotated by yaw.
struct Building {
  double x = 0, y = 0, yaw = 0;
  double length = 10, width = 10, height = 20;
};

// A vertical cylinder; a lamp adds a horizontal arm of arm_length at the top, pointing along arm_yaw.
struct Pole {
  double x = 0, y = 0;
  double radius = 0.1, height = 6.0;
  double arm_length = 0.0, arm_yaw = 0.0;
};

// A trunk (cylinder) with a roughly spherical crown centred at trunk_height + crown_radius * 0.7.
struct Tree {
  double x = 0, y = 0;
  double trunk_radius = 0.15, trunk_height = 2.5, crown_radius = 1.8;
};

// A hedge-like shrub: an ellipsoid of the given extents standing on the ground.
struct Shrub {
  double x = 0, y = 0, yaw = 0;
  double length = 2.0, width = 0.8, height = 1.0;
};

// Vehicle body proportions. The footprint (plan-view bounding rectangle) is exactly length x width,
// centred at the vehicle's reference point; mirrors stay inside the width. Defaults: Lexus RX450h
// (docs/design.md §2).
struct VehicleShape {
  double length = 4.89;
  double width = 1.92;
  double height = 1.70;
  double corner_radius = 0.35;     // plan-view rounding of the body corners
  double ground_clearance = 0.20;  // underside of the body
  double belt_height = 1.00;       // where the glasshouse starts
  double cabin_inset = 0.14;       // each side, glasshouse narrower than the body
  double hood_length = 1.25;       // front overhang of the body ahead of the windscreen base
  double windscreen_run = 0.75;    // horizontal run of the sloped windscreen
  double rear_slope_run = 0.35;    // horizontal run of the sloped rear window
  double wheel_radius = 0.37;
  double wheel_width = 0.24;
  double wheelbase = 2.79;
};

// Trajectories: the vehicle's footprint-centre pose as a function of time.
struct StaticPose {
  Pose2 pose;
};
// Spinning in place about (x, y) at a constant rate (the pilot experiment).
struct Spin {
  double x = 0, y = 0;
  double yaw0 = 0;        // yaw at time t0
  double rate_rad_s = 0;  // counter-clockwise positive
  TimeNs t0 = 0;
};
struct TimedPose {
  TimeNs t = 0;
  Pose2 pose;
};
// Time-stamped poses, held before the first and after the last. Between them either piecewise-linear in
// x, y and (shortest-way) yaw, or, with `smooth`, a cubic Hermite path through the points (tangents by
// central differences in time) with the yaw along the direction of motion, as a driven car moves: no
// sideways crabbing and no jumps of the yaw. Its curvature is not continuous: the yaw rate steps at each
// inner point. (The points' yaw then only matters where the vehicle stands still.)
struct Waypoints {
  std::vector<TimedPose> points;
  bool smooth = false;
};
using Trajectory = std::variant<StaticPose, Spin, Waypoints>;

struct Vehicle {
  std::uint32_t id = 0;
  VehicleShape shape;
  Trajectory trajectory;
};

struct Scene {
  Ground ground;
  std::vector<Building> buildings;
  std::vector<Pole> poles;
  std::vector<Tree> trees;
  std::vector<Shrub> shrubs;
  std::vector<Vehicle> vehicles;
  Reflectivity reflectivity;
};

// Simulated sensor noise (docs/design.md §2: the paper's simulator defaults).
struct NoiseModel {
  double range_sigma_m = 0.02;
  double angle_sigma_rad = 0.001;
  std::uint64_t seed = 1;
};

}  // namespace rsu::sim
