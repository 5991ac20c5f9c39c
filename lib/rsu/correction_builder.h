// Turns a size-corrected fix (perception/size_correction.h) into the wire Correction (proto/v2i.proto,
// messages.h): pose of the footprint centre, covariance, the sweep time and the quality block.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "common/time.h"
#include "perception/rectangle_fit.h"
#include "perception/size_correction.h"
#include "v2i/messages.h"

namespace rsu::core {

// How the fix settled the yaw, in the wire's terms. The wire's PRIOR / GEOMETRY say which way the
// length axis lies (the off-by-90 deg question, DESIGN.md §1); Algorithm 1's "longest edge is the
// length" and an unresolved fix are reported as UNRESOLVED.
v2i::YawResolution to_wire(perception::AmbiguityResolution resolution);

// Faces of the fitted rectangle the LiDAR saw (0..2; 1 = one edge, 2 = an L).
std::uint32_t faces_seen(const perception::RectangleFit& fit);

struct CorrectionInputs {
  std::uint64_t rsu_id = 0;
  std::uint64_t vehicle_id = 0;
  std::uint32_t sequence = 0;               // the RSU's per-vehicle counter
  std::uint32_t announcement_sequence = 0;  // of the announcement whose size and yaw prior were used
  TimeNs sweep_time = 0;                    // mean firing time of the vehicle's points
  std::size_t points_used = 0;
};

// `fix` must be ok(). range_m is the horizontal distance from the LiDAR to the alignment corner.
v2i::Correction make_correction(const CorrectionInputs& inputs, const perception::CorrectedPose& fix,
                                const perception::RectangleFit& fit, const Eigen::Vector2d& lidar_xy);

}  // namespace rsu::core
