// SPDX-License-Identifier: Apache-2.0
// How well a box of known size agrees with a vehicle's points, in the box's frame: points outside it
// speak against it, and so do stretches of its LiDAR-facing outline without points (a face the LiDAR
// should have seen but did not). Decides which fitted axis is the vehicle's length when the vehicle's
// yaw prior does not (size_correction.h), and refuses boxes that do not hold the points.
#pragma once

#include <span>

#include <Eigen/Core>

namespace rsu::perception {

struct CorrectionConfig;

// Share of the points farther than `tolerance` outside the box (centre, half sizes).
double outside_fraction(std::span<const Eigen::Vector2d> local, const Eigen::Vector2d& centre,
                        const Eigen::Vector2d& half, double tolerance);

// In [0, 2]: the share of points outside the box plus the share (weighted by the cosine of incidence) of
// its LiDAR-facing outline that no point within cover_radius covers.
double box_inconsistency(std::span<const Eigen::Vector2d> local, const Eigen::Vector2d& lidar_local,
                         const Eigen::Vector2d& centre, const Eigen::Vector2d& half, double cover_radius,
                         const CorrectionConfig& config);

}  // namespace rsu::perception
