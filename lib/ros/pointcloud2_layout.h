// SPDX-License-Identifier: Apache-2.0
// sensor_msgs/PointCloud2 -> LidarPoints, pure (no DDS types: the DDS edge fills PointCloud2View
// from the received sample). The layout is read from the message's `fields`:
//   x, y, z      required, FLOAT32 or FLOAT64, count >= 1 (the first element is used)
//   intensity    optional, any numeric datatype (0..255 for Velodyne reflectivity)
//   ring         optional, any numeric datatype, a whole number within [0, 65535]
//   time         optional, relative to header.stamp: FLOAT32/FLOAT64 in seconds (Velodyne's ROS
//                drivers: per-point float32 seconds, positive or negative), integers in nanoseconds
//   t            optional, integer nanoseconds relative to header.stamp (Ouster's ROS drivers); used
//                only when there is no `time`
// Without a time field every point gets header.stamp. The azimuth is the beam's, from x and y
// (clockwise from sensor +x seen from above, as LidarPoint says); z up.
//
// A layout is rejected whole, with one reason, when it cannot be read safely: fields overlapping or
// reaching past point_step, sizes overflowing 32 bits, row_step shorter than a row, data shorter than
// height x row_step says, more points than `max_points`. Points whose x, y or z is not finite
// (organised clouds mark holes with NaN, whatever is_dense says), whose ring is not a ring number or
// whose time is not finite are skipped and counted.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/time.h"
#include "lidar/point.h"

namespace rsu::ros {

// sensor_msgs/PointField datatype constants.
enum class PointDatatype : std::uint8_t {
  kInt8 = 1,
  kUint8 = 2,
  kInt16 = 3,
  kUint16 = 4,
  kInt32 = 5,
  kUint32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};
// Bytes of one element; 0 for a value outside the enumeration.
std::uint32_t datatype_size(std::uint8_t datatype);

struct PointFieldView {
  std::string_view name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 0;
};

struct PointCloud2View {
  TimeNs stamp = 0;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::span<const PointFieldView> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::span<const std::uint8_t> data;
  bool is_dense = false;
};

enum class CloudReject : std::uint8_t {
  kNone = 0,
  kMissingXyz,         // no x, y or z field
  kCoordinateType,     // x, y or z not FLOAT32/FLOAT64, or count 0
  kUnknownDatatype,    // a field's datatype is not one of the eight
  kDuplicateField,     // two fields with one name
  kFieldOutsidePoint,  // a field reaches past point_step
  kOverlappingFields,  // two fields share bytes
  kSizeOverflow,       // offset + count x size or width x point_step beyond 32 bits
  kRowStepTooSmall,    // row_step < width x point_step
  kDataTooShort,       // data shorter than height x row_step
  kTooManyPoints,      // height x width > max_points
  kCount,
};
const char* to_string(CloudReject reason);

struct CloudLimits {
  // A 128-laser sensor in dual return mode makes ~0.5 M points per rotation; 4 M leaves room for
  // accumulated clouds while keeping a forged count from allocating gigabytes.
  std::uint64_t max_points = 4'000'000;
};

enum class RingOrder : std::uint8_t {
  kChannel,    // ring = laser index in firing order (this project's packets and PCD files)
  kElevation,  // ring = rank by elevation, 0 the lowest beam (the Velodyne ROS drivers' ring)
};

// Where a usable field is in a point.
struct FieldSlot {
  bool present = false;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
};

struct PointCloud2Layout {
  FieldSlot x, y, z, intensity, ring, time;
  bool time_in_seconds = false;  // floating time field; otherwise integer nanoseconds
  bool big_endian = false;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
};

struct LayoutResult {
  CloudReject reject = CloudReject::kNone;
  PointCloud2Layout layout;
  bool ok() const { return reject == CloudReject::kNone; }
};

LayoutResult parse_layout(const PointCloud2View& cloud, const CloudLimits& limits = {});

struct CloudDecodeStats {
  std::uint64_t points = 0;              // appended to the output
  std::uint64_t non_finite_skipped = 0;  // x, y or z NaN or infinite
  std::uint64_t bad_ring_skipped = 0;    // ring not a whole number in [0, 65535] (or beyond the map)
  std::uint64_t bad_time_skipped = 0;    // time not finite, or beyond the clock's range
};

// Appends the cloud's points (row by row) to `out`; `layout` must come from parse_layout(cloud).
// `elevation_to_channel`, used with RingOrder::kElevation, maps a ring rank to the channel index
// (ring_rank_to_channel()); a rank outside it is a bad ring.
CloudDecodeStats decode_points(const PointCloud2View& cloud, const PointCloud2Layout& layout,
                               std::span<const std::uint16_t> elevation_to_channel,
                               std::vector<lidar::LidarPoint>& out);

// Channel indices sorted by elevation, lowest first (ties keep channel order): rank -> channel.
std::vector<std::uint16_t> ring_rank_to_channel(std::span<const double> elevation_deg);

}  // namespace rsu::ros
