// SPDX-License-Identifier: Apache-2.0
#include "ros/ros_time.h"

#include <limits>

namespace rsu::ros {

std::optional<TimeNs> from_ros_time(RosTime t) {
  if (t.nanosec >= static_cast<std::uint32_t>(kNsPerSecond))
    return std::nullopt;
  return static_cast<TimeNs>(t.sec) * kNsPerSecond + static_cast<TimeNs>(t.nanosec);
}

RosTime to_ros_time(TimeNs t) {
  constexpr TimeNs kMin = static_cast<TimeNs>(std::numeric_limits<std::int32_t>::min()) * kNsPerSecond;
  constexpr TimeNs kMax =
      static_cast<TimeNs>(std::numeric_limits<std::int32_t>::max()) * kNsPerSecond + (kNsPerSecond - 1);
  if (t <= kMin)
    return RosTime{std::numeric_limits<std::int32_t>::min(), 0};
  if (t >= kMax)
    return RosTime{std::numeric_limits<std::int32_t>::max(), static_cast<std::uint32_t>(kNsPerSecond - 1)};
  TimeNs sec = t / kNsPerSecond;
  TimeNs ns = t % kNsPerSecond;
  if (ns < 0) {  // floor division: nanosec is never negative
    ns += kNsPerSecond;
    --sec;
  }
  return RosTime{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(ns)};
}

}  // namespace rsu::ros
