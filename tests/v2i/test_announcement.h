// SPDX-License-Identifier: Apache-2.0
// A plausible announcement for tests: a Lexus RX450h (docs/design.md §2) reporting its rear axle.
#pragma once

#include <cstdint>

#include "common/time.h"
#include "v2i/messages.h"

namespace rsu::v2i::testing {

inline VehicleAnnouncement make_announcement(std::uint64_t id, std::uint32_t sequence,
                                             TimeNs generation_time) {
  VehicleAnnouncement a;
  a.vehicle_id = id;
  a.sequence = sequence;
  a.generation_time = generation_time;
  a.size = {4.89, 1.92, 1.70};
  a.reference_offset = {-1.35, 0.0};
  a.pose = {120.5, -33.25, 0.4};
  a.pose_covariance << 0.04, 0.01, 0.0, 0.01, 0.05, 0.0, 0.0, 0.0, 0.001;
  a.speed_mps = 8.5;
  a.yaw_rate_rps = 0.02;
  a.reply_to = {"192.0.2.17", 47001};
  return a;
}

}  // namespace rsu::v2i::testing
