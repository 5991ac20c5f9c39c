// SPDX-License-Identifier: Apache-2.0
// PCD files of LiDAR points (PCL's format, read and written here: pcd_header.h). write_pcd's fields: x y z
// intensity (float), ring (uint16), azimuth (float, rad), time (float64, seconds on the common clock).
// Reading accepts any PCD that has x, y, z; intensity, ring, azimuth and time are used when present (as
// the daemon's PCD replay input).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "lidar/point.h"

namespace rsu::io {

class PcdError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void write_pcd(const std::string& path, const std::vector<lidar::LidarPoint>& points);
// One rotation as rsu-decode writes it (README, "rsu-decode"): fields x y z intensity (float32), ring
// (uint16) and time (uint32, ns since `rotation_start_ns`, the rotation's first point). Throws PcdError
// naming the file when it cannot be written, or std::invalid_argument for a point before the start or
// more than 4.29 s after it.
void write_rotation_pcd(const std::string& path, const std::vector<lidar::LidarPoint>& points,
                        TimeNs rotation_start_ns);
// Any PCD v0.7 file: ascii, binary or binary_compressed data, fields of any numeric type and count (the
// first value is used). Throws PcdError naming the file and what is wrong (missing file, malformed
// header, no x/y/z, too little data, a ring or time that does not fit).
std::vector<lidar::LidarPoint> read_pcd(const std::string& path);

}  // namespace rsu::io
