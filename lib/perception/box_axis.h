// SPDX-License-Identifier: Apache-2.0
// Where a box of known length and width sits along one of its axes, from the vehicle's points and what the
// LiDAR could have seen (the improved size correction, size_correction.h).
//
// Along an axis the box [c - D/2, c + D/2] must hold every point (containment). Each of its two sides is
// then one of:
//  - a face: lower-body points (the full footprint: doors, bumpers; below lower_body_fraction of the
//    announced height, at a side where they make no face up to full_plan_height_m, and at the front and
//    back below the bonnet: BoxPoint) spread along a side that faces the LiDAR. The side is their outer
//    envelope (face_envelope.h), c = envelope -+ D/2.
//  - an end: the extreme point on that side is a lower-body point and the LiDAR would have seen the body
//    continue beyond it (field of view, self-occlusion): the body ends within end_allowance_m of it
//    (rounded corners, the azimuth step).
//  - an upper edge: the extreme is higher up (roof, glasshouse, bonnet): the footprint may go on
//    anywhere beyond it (a laser's trace leaves a roof through whichever edge it meets): containment only.
//  - unobserved: the LiDAR could not have seen beyond it (its lowest laser passes above the car there, or
//    the car hides it): only containment bounds the side.
// With a face the axis is anchored on it; with two ends spanning the known size, at their middle (stating
// the span's shortfall as a uniform spread: a rounded corner may cut one end and not the other); else c
// is the middle of the interval the sides and containment leave, and its variance that of a uniform
// error over it: the fix says how little the points decide instead of guessing an end.
#pragma once

#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "perception/fix_covariance.h"
#include "perception/lidar_geometry.h"

namespace rsu::perception {

struct CorrectionConfig;
class FaceEnvelopeMemo;

// A point in the box's frame: (along axis 0, along axis 1), its height above the road, whether it can
// be on the lower body (whose outline is the footprint's: the sides), whether it can be on the sides where
// the lower body shows no face (below full_plan_height_m too: side_body_height), whether it lies low enough
// to be on the front and back (below the bonnet: end_body_height), and its horizontal range from the LiDAR.
struct BoxPoint {
  Eigen::Vector2d local = Eigen::Vector2d::Zero();
  double height = 0.0;
  bool lower_body = false;
  bool side_body = false;
  bool end_body = false;
  double range = 0.0;
};

struct AxisEstimate {
  double centre = 0.0;
  // Where the evidence lies on the OTHER axis (a face's points, the ends, all points): a yaw error
  // turns the box about it, moving the centre along this axis by the yaw error times their distance.
  double across = 0.0;
  AxisEvidence evidence;
  bool contained = true;  // the points fit within the known size on this axis (within noise)
};

struct AxisContext {
  std::span<const BoxPoint> points;
  Eigen::Vector2d lidar_local = Eigen::Vector2d::Zero();
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // the box frame's origin (map)
  Eigen::Vector2d e0 = Eigen::Vector2d::UnitX();     // axis 0 (map)
  Eigen::Vector2d e1 = Eigen::Vector2d::UnitY();     // axis 1 (map)
  Eigen::Vector2d dims = Eigen::Vector2d::Zero();    // the known size along axis 0 and axis 1
  int length_axis = 0;                               // which of them is the vehicle's length
  double vehicle_height = 1.7;
  double end_height = 1.0;    // up to which the body surely reaches at its front and back (the bonnet)
  double noise_sigma = 0.03;  // the points' noise across a face
  double yaw_sigma = 0.0;     // how uncertain the frame's direction is (rad)
  // Where the faces' envelopes are estimated: a memo shared by the placements of one correction (the same
  // face in the same frame is not estimated twice), or none.
  FaceEnvelopeMemo* envelopes = nullptr;
};

// Both axes of the box (axis 0, axis 1).
std::array<AxisEstimate, 2> estimate_axes(const AxisContext& ctx, const LidarGeometry& lidar,
                                          const CorrectionConfig& config);

}  // namespace rsu::perception
