// SPDX-License-Identifier: Apache-2.0
// What one fitted edge of a vehicle's rectangle tells about its yaw (the improved correction,
// size_correction.h): only its points that lie on a vertical surface of the body count (below the bonnet,
// or above it rising over several heights or spreading in range: one laser's trace across a roof or a
// bonnet is a line across the line of sight whatever the heading; a car's bonnet may lie as low as
// min_bonnet_height_m, so one laser's arc at one range between there and end_height does not count either),
// over the extent they span along the face (a least-squares line's direction is as well known as its points'
// spread makes it, not the fitted edge's length), with the body's departure from a plane (fix_covariance.h).
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

// Up to which height above the road (end_height or lower_height) edge `edge`'s points count as the lower
// body when informative_face judges it. A face may be an end, whose lower body reaches the bonnet only
// (end_height); a side, surely one by its length, reaches the lower body (lower_height) where its returns up
// to there lie on one vertical surface: the upper half of them, by height, within side_step_m of the lower
// half's line. Tall vehicles' sides rise vertical far above the bonnet: a VLP-32C 8 m up saw a box truck's
// 7.4 m side 22 m away with one laser at 1.3-2.5 m, all of it judged above the bonnet and not shown
// vertical, so the vehicle's heading decided; the fix was 5.9 deg off and 0.20 m off across, stating 0.06
// m (a third pilot matrix, kept out of the repository). But a van's glass, 5 cm in above its belt line at
// 1.2 m, lies below 55 % of its 2.45 m: taken for the lower body, it turned the sides 2 deg while they
// stated 0.6 deg (`rsu-pilot matrix`), and its returns there lie off the line of those below.
double face_lower_height(std::span<const Eigen::Vector3d> points, const LidarGeometry& lidar,
                         const CorrectionConfig& config, double end_height, double lower_height,
                         const RectangleFit& fit, std::size_t edge, const VehicleSize& size);

}  // namespace rsu::perception
