// SPDX-License-Identifier: Apache-2.0
// One LiDAR return and one frame of returns, as every LiDAR source (simulator, Velodyne packets, PCD,
// DDS) delivers them to the perception pipeline.
#pragma once

#include <cstdint>
#include <vector>

#include "common/time.h"

namespace rsu::lidar {

// Which echo of its firing a point is, as bit flags: a multi-return sensor reports the strongest and the
// last echo (the only echo is both; a second-strongest one is neither). A single-return sensor's point
// carries the flag of the mode it runs in.
constexpr std::uint8_t kStrongestReturn = 1;
constexpr std::uint8_t kLastReturn = 2;

struct LidarPoint {
  float x = 0.0F;  // metres, sensor frame (x forward, y left, z up) unless a frame says otherwise
  float y = 0.0F;
  float z = 0.0F;
  float intensity = 0.0F;                // 0..255, the packet's reflectivity byte
  std::uint16_t ring = 0;                // laser index in channel (firing) order, as in the packet
  std::uint8_t echo = kStrongestReturn;  // kStrongestReturn | kLastReturn flags (above)
  float azimuth_rad = 0.0F;  // beam rotation angle, clockwise seen from above, 0 at sensor +x, [0, 2 pi)
  TimeNs time_ns = 0;        // when this laser fired, common clock
};

struct LidarFrame {
  TimeNs start_ns = 0;  // first firing of the rotation
  TimeNs end_ns = 0;    // last firing of the rotation
  std::vector<LidarPoint> points;
};

}  // namespace rsu::lidar
