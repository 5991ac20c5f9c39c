// PCD files of LiDAR points through PCL. Fields: x y z intensity (float), ring (uint16), azimuth (float,
// rad), time (float64, seconds on the common clock). Reading accepts any PCD that has x, y, z; intensity,
// ring, azimuth and time are used when present (as the daemon's PCD replay input).
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

void write_pcd(const std::string& path, const std::vector<LidarPoint>& points);
// Throws PcdError naming the file and what is wrong (missing file, no x/y/z, unsupported field type).
std::vector<LidarPoint> read_pcd(const std::string& path);

}  // namespace rsu::io
