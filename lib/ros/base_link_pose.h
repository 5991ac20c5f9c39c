// SPDX-License-Identifier: Apache-2.0
// An RSU's fix of a vehicle turned into what Autoware's ekf_localizer takes as a pose input: the pose of
// the vehicle's base_link in the vehicle's map frame, pure (rsu-autoware-sidecar does the DDS).
//
// The RSU publishes the footprint box centre, z = 0, and a box yaw that is only known modulo pi (a
// rectangle looks the same turned by 180 degrees; paper Sec. 3, docs/design.md §1), with (x, y, yaw)
// covariance and z, roll, pitch unknown (correction_pose.h). The vehicle knows its own heading (NDT): the
// box yaw's branch nearest it is the heading; base_link = box centre + R(yaw) * offset, the offset being
// base_link minus the box centre in the vehicle frame (Autoware's base_link is the rear axle's centre:
// about -1.4 m for a car); the yaw's variance reaches x and y through d(R(yaw) offset)/d(yaw). z and its
// variance are the vehicle's own (the RSU measures no height); roll and pitch stay unknown.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "common/time.h"
#include "ros/correction_pose.h"

namespace rsu::ros {

struct StampedPose {
  TimeNs stamp = 0;
  RosPoseWithCovariance pose;
};

struct BaseLinkConfig {
  Eigen::Vector2d base_link_offset{0.0, 0.0};  // base_link minus box centre, vehicle frame (m)
  // The own pose nearest the fix's sweep time in time, at most this far from it, resolves the yaw.
  double max_own_pose_age_s = 0.5;
  // A box yaw farther than this from the own heading (modulo pi) is refused: near 90 degrees the branch
  // is a guess, and an RSU's off-by-90-degree fit (paper Sec. 4) lands there.
  double max_heading_disagreement_rad = 0.5;
};

enum class BaseLinkRefusal : std::uint8_t {
  kNone,
  kMalformedFix,         // non-finite, not a unit quaternion, covariance not positive definite
  kNoOwnPose,            // none within max_own_pose_age_s of the sweep time
  kHeadingDisagreement,  // beyond max_heading_disagreement_rad
  kCount,
};
std::string_view refusal_name(BaseLinkRefusal refusal);

struct BaseLinkResult {
  BaseLinkRefusal refusal = BaseLinkRefusal::kNone;
  RosPoseWithCovariance pose;         // valid when refusal == kNone
  double yaw_disagreement_rad = 0.0;  // box yaw minus own heading on the nearest branch
};

// Yaw (about +z) of a quaternion (x, y, z, w), in (-pi, pi].
double yaw_of(const std::array<double, 4>& quaternion);

// The base_link pose for the RSU's fix `fix` (its stamp the sweep time), given the vehicle's own poses
// `own` (any order; the one nearest the sweep time is used).
BaseLinkResult base_link_pose(const StampedPose& fix, std::span<const StampedPose> own,
                              const BaseLinkConfig& config);

}  // namespace rsu::ros
