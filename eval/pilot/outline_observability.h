// SPDX-License-Identifier: Apache-2.0
// Whether a frame's points show where the vehicle's footprint is: an oracle that knows the true pose, used
// to tell a fix method's misses from the sensor's (issue 12: "fixes that hold from 2 m to 8 m mounts").
//
// A fix from the announced length, width and height places the footprint from the points that lie on its
// outline (a door, a bumper, a flat van's or bus's end at any height) or from containment (the points
// span nearly the whole length or width). The roof and glasshouse lie inside the outline by amounts the
// announcement does not carry (a bonnet's length, a window's inset), so from them alone the footprint's
// place is open by that much. The oracle counts, in the vehicle's true frame, the points within
// tolerance_m of each end and each side of the footprint. An axis (length, width) is pinned when
// min_points of them lie at one of its two edges, or when the points span its extent to within
// 2 x tolerance_m; the outline is seen when both axes are pinned. Where it is not, a method told only the
// size cannot place the box to better than the tolerance except by luck; where it is, it could.
#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

#include "common/pose.h"

namespace rsu::eval {

struct OutlineObservabilityConfig {
  double tolerance_m = 0.05;  // half the fix's 0.10 m goal
  std::size_t min_points = 3;
};

struct OutlineObservability {
  bool length_pinned = false;
  bool width_pinned = false;
  bool seen() const { return length_pinned && width_pinned; }
};

// points: the vehicle's points (map frame); truth: its footprint centre and yaw; length, width: its size.
OutlineObservability observe_outline(std::span<const Eigen::Vector3d> points, const Pose2& truth,
                                     double length, double width,
                                     const OutlineObservabilityConfig& config = {});

}  // namespace rsu::eval
