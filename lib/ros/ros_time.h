// SPDX-License-Identifier: Apache-2.0
// builtin_interfaces/Time <-> the common clock (TimeNs, docs/design.md §3). ROS time is {int32 sec,
// uint32 nanosec in [0, 1e9)}: nanosec always adds, so times before the epoch have a negative sec.
#pragma once

#include <cstdint>
#include <optional>

#include "common/time.h"

namespace rsu::ros {

struct RosTime {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};

// nullopt when nanosec >= 1e9 (not a ROS time).
std::optional<TimeNs> from_ros_time(RosTime t);
// Saturates at the int32 seconds range (1901..2038): beyond it ROS's Time cannot say the time.
RosTime to_ros_time(TimeNs t);

}  // namespace rsu::ros
