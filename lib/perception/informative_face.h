// SPDX-License-Identifier: Apache-2.0
// What one fitted edge of a vehicle's rectangle tells about its yaw (the improved correction,
// size_correction.h): only its points that lie on a vertical surface of the body count (below the bonnet,
// or above it rising over several heights or spreading in range: one laser's trace across a roof or a
// bonnet is a line across the line of sight whatever the heading), over the extent they span along the
// face (a least-squares line's direction is as well known as its points' spread makes it, not the fitted
// edge's length), with the body's departure from a plane (fix_covariance.h).
#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

#include "perception/fix_covariance.h"
#include "perception/lidar_geometry.h"
#include "perception/rectangle_fit.h"

namespace rsu::perception {

struct CorrectionConfig;
struct VehicleSize;

// Edge `edge` (0..3) of `fit` seen from `lidar`; points: the vehicle's (map frame, finite), ranks: their
// lasers' (LaserLookup::ranks from lidar.position; the fix ranks them once for all its faces); end_height:
// up to which height above the road a point can be on the footprint's front or back (the bonnet);
// noise_sigma: the points' noise across a face; size: the vehicle's announced (a face spanning a whole side
// or end holds both its rounded corners).
FaceEvidence informative_face(std::span<const Eigen::Vector3d> points, std::span<const std::size_t> ranks,
                              const LidarGeometry& lidar, const CorrectionConfig& config, double end_height,
                              double noise_sigma, const RectangleFit& fit, std::size_t edge,
                              const VehicleSize& size);

}  // namespace rsu::perception
