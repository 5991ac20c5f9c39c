// SPDX-License-Identifier: Apache-2.0
#include "ros/pointcloud2_layout.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>
#include <numeric>

namespace rsu::ros {

namespace {

constexpr std::uint64_t kU32Max = 0xFFFF'FFFFULL;

// Reads one element of `datatype` at `p`, stored with the cloud's byte order, as a double.
template <typename T>
T load(const std::uint8_t* p, bool big_endian) {
  std::array<std::uint8_t, sizeof(T)> bytes{};
  std::memcpy(bytes.data(), p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big))
    std::reverse(bytes.begin(), bytes.end());
  return std::bit_cast<T>(bytes);
}

double read_value(const std::uint8_t* p, std::uint8_t datatype, bool big_endian) {
  switch (static_cast<PointDatatype>(datatype)) {
    case PointDatatype::kInt8:
      return load<std::int8_t>(p, big_endian);
    case PointDatatype::kUint8:
      return load<std::uint8_t>(p, big_endian);
    case PointDatatype::kInt16:
      return load<std::int16_t>(p, big_endian);
    case PointDatatype::kUint16:
      return load<std::uint16_t>(p, big_endian);
    case PointDatatype::kInt32:
      return load<std::int32_t>(p, big_endian);
    case PointDatatype::kUint32:
      return load<std::uint32_t>(p, big_endian);
    case PointDatatype::kFloat32:
      return static_cast<double>(load<float>(p, big_endian));
    case PointDatatype::kFloat64:
      return load<double>(p, big_endian);
  }
  return std::numeric_limits<double>::quiet_NaN();  // unreachable after parse_layout
}

bool is_float(std::uint8_t datatype) {
  return datatype == static_cast<std::uint8_t>(PointDatatype::kFloat32) ||
         datatype == static_cast<std::uint8_t>(PointDatatype::kFloat64);
}

float beam_azimuth(float x, float y) {
  // Clockwise from +x seen from above (LidarPoint), in [0, 2 pi); float rounding can reach 2 pi.
  double a = std::atan2(-static_cast<double>(y), static_cast<double>(x));
  if (a < 0)
    a += 2 * std::numbers::pi;
  const auto f = static_cast<float>(a);
  return f >= static_cast<float>(2 * std::numbers::pi) ? 0.0F : f;
}

}  // namespace

std::uint32_t datatype_size(std::uint8_t datatype) {
  switch (datatype) {
    case 1:
    case 2:
      return 1;
    case 3:
    case 4:
      return 2;
    case 5:
    case 6:
    case 7:
      return 4;
    case 8:
      return 8;
    default:
      return 0;
  }
}

const char* to_string(CloudReject reason) {
  switch (reason) {
    case CloudReject::kNone:
      return "none";
    case CloudReject::kMissingXyz:
      return "missing_xyz";
    case CloudReject::kCoordinateType:
      return "coordinate_type";
    case CloudReject::kUnknownDatatype:
      return "unknown_datatype";
    case CloudReject::kDuplicateField:
      return "duplicate_field";
    case CloudReject::kFieldOutsidePoint:
      return "field_outside_point";
    case CloudReject::kOverlappingFields:
      return "overlapping_fields";
    case CloudReject::kSizeOverflow:
      return "size_overflow";
    case CloudReject::kRowStepTooSmall:
      return "row_step_too_small";
    case CloudReject::kDataTooShort:
      return "data_too_short";
    case CloudReject::kTooManyPoints:
      return "too_many_points";
    case CloudReject::kCount:
      break;
  }
  return "unknown";
}

namespace {

// The layout's slot for field `f` (x, y, z, intensity, ring, time), or none: an unknown name, no
// values, or a floating `t` (Ouster's t is integer nanoseconds; a floating one is someone else's).
FieldSlot* slot_for(const PointFieldView& f, PointCloud2Layout& l) {
  if (f.count == 0 || (f.name == "t" && is_float(f.datatype)))
    return nullptr;
  if (f.name == "x")
    return &l.x;
  if (f.name == "y")
    return &l.y;
  if (f.name == "z")
    return &l.z;
  if (f.name == "intensity")
    return &l.intensity;
  if (f.name == "ring")
    return &l.ring;
  if (f.name == "time" || (f.name == "t" && !l.time.present))
    return &l.time;
  return nullptr;
}

// What is wrong with the cloud's size (points, rows, data) given its point step, if anything.
CloudReject size_problem(const PointCloud2View& cloud, const CloudLimits& limits) {
  const std::uint64_t points = std::uint64_t{cloud.width} * cloud.height;
  if (points > limits.max_points)
    return CloudReject::kTooManyPoints;
  const std::uint64_t row_bytes = std::uint64_t{cloud.width} * cloud.point_step;
  if (row_bytes > kU32Max)
    return CloudReject::kSizeOverflow;
  if (cloud.row_step < row_bytes)
    return CloudReject::kRowStepTooSmall;
  // The last row needs only its points, not its padding; every earlier row its whole row_step.
  const std::uint64_t needed = cloud.height == 0 || cloud.width == 0
                                   ? 0
                                   : std::uint64_t{cloud.height - 1} * cloud.row_step + row_bytes;
  if (cloud.data.size() < needed)
    return CloudReject::kDataTooShort;
  return CloudReject::kNone;
}

}  // namespace

LayoutResult parse_layout(const PointCloud2View& cloud, const CloudLimits& limits) {
  LayoutResult r;
  auto reject = [&r](CloudReject why) {
    r.reject = why;
    return r;
  };
  PointCloud2Layout& l = r.layout;
  l.big_endian = cloud.is_bigendian;
  l.width = cloud.width;
  l.height = cloud.height;
  l.point_step = cloud.point_step;
  l.row_step = cloud.row_step;

  // Every field's bytes, to find overlaps: [begin, end) within the point.
  struct Extent {
    std::uint64_t begin, end;
  };
  std::vector<Extent> extents;
  extents.reserve(cloud.fields.size());
  for (std::size_t i = 0; i < cloud.fields.size(); ++i) {
    const PointFieldView& f = cloud.fields[i];
    const std::uint32_t size = datatype_size(f.datatype);
    if (size == 0)
      return reject(CloudReject::kUnknownDatatype);
    for (std::size_t j = 0; j < i; ++j) {
      if (cloud.fields[j].name == f.name)
        return reject(CloudReject::kDuplicateField);
    }
    const std::uint64_t end = std::uint64_t{f.offset} + std::uint64_t{size} * f.count;
    if (end > kU32Max)
      return reject(CloudReject::kSizeOverflow);
    if (end > cloud.point_step)
      return reject(CloudReject::kFieldOutsidePoint);
    if (f.count > 0)
      extents.push_back({f.offset, end});

    FieldSlot* slot = slot_for(f, l);
    if (slot == nullptr)
      continue;
    *slot = FieldSlot{true, f.offset, f.datatype};
    if (slot == &l.time)
      l.time_in_seconds = is_float(f.datatype);
  }
  std::sort(extents.begin(), extents.end(),
            [](const Extent& a, const Extent& b) { return a.begin < b.begin; });
  for (std::size_t i = 1; i < extents.size(); ++i) {
    if (extents[i].begin < extents[i - 1].end)
      return reject(CloudReject::kOverlappingFields);
  }
  for (const std::string_view name : {"x", "y", "z"}) {
    const auto it = std::find_if(cloud.fields.begin(), cloud.fields.end(),
                                 [name](const PointFieldView& f) { return f.name == name; });
    if (it == cloud.fields.end())
      return reject(CloudReject::kMissingXyz);
    if (!is_float(it->datatype) || it->count == 0)
      return reject(CloudReject::kCoordinateType);
  }

  r.reject = size_problem(cloud, limits);
  return r;
}

CloudDecodeStats decode_points(const PointCloud2View& cloud, const PointCloud2Layout& l,
                               std::span<const std::uint16_t> elevation_to_channel,
                               std::vector<lidar::LidarPoint>& out) {
  CloudDecodeStats s;
  const bool be = l.big_endian;
  out.reserve(out.size() + std::size_t{l.width} * l.height);
  for (std::uint32_t row = 0; row < l.height; ++row) {
    const std::uint8_t* row_data = cloud.data.data() + std::size_t{row} * l.row_step;
    for (std::uint32_t col = 0; col < l.width; ++col) {
      const std::uint8_t* src = row_data + std::size_t{col} * l.point_step;
      lidar::LidarPoint p;
      p.x = static_cast<float>(read_value(src + l.x.offset, l.x.datatype, be));
      p.y = static_cast<float>(read_value(src + l.y.offset, l.y.datatype, be));
      p.z = static_cast<float>(read_value(src + l.z.offset, l.z.datatype, be));
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        ++s.non_finite_skipped;
        continue;
      }
      if (l.intensity.present)
        p.intensity = static_cast<float>(read_value(src + l.intensity.offset, l.intensity.datatype, be));
      if (l.ring.present) {
        const double r = read_value(src + l.ring.offset, l.ring.datatype, be);
        // Casting a value outside uint16 (or NaN) would be undefined behaviour.
        if (!(r >= 0.0 && r <= 65535.0) || r != std::floor(r)) {
          ++s.bad_ring_skipped;
          continue;
        }
        p.ring = static_cast<std::uint16_t>(r);
        if (!elevation_to_channel.empty()) {
          if (p.ring >= elevation_to_channel.size()) {
            ++s.bad_ring_skipped;
            continue;
          }
          p.ring = elevation_to_channel[p.ring];
        }
      }
      p.time_ns = cloud.stamp;
      if (l.time.present) {
        const double v = read_value(src + l.time.offset, l.time.datatype, be);
        const double offset_ns = l.time_in_seconds ? v * 1e9 : v;
        // The offset must keep the sum inside TimeNs (int64, +-292 years); anything that large is junk.
        if (!(std::abs(offset_ns) < 1e18) ||
            (offset_ns > 0
                 ? cloud.stamp > std::numeric_limits<TimeNs>::max() - static_cast<TimeNs>(offset_ns)
                 : cloud.stamp < std::numeric_limits<TimeNs>::min() - static_cast<TimeNs>(offset_ns))) {
          ++s.bad_time_skipped;
          continue;
        }
        p.time_ns = cloud.stamp + static_cast<TimeNs>(std::llround(offset_ns));
      }
      p.azimuth_rad = beam_azimuth(p.x, p.y);
      out.push_back(p);
      ++s.points;
    }
  }
  return s;
}

std::vector<std::uint16_t> ring_rank_to_channel(std::span<const double> elevation_deg) {
  std::vector<std::uint16_t> channels(elevation_deg.size());
  std::iota(channels.begin(), channels.end(), std::uint16_t{0});
  std::stable_sort(channels.begin(), channels.end(),
                   [&](std::uint16_t a, std::uint16_t b) { return elevation_deg[a] < elevation_deg[b]; });
  return channels;
}

}  // namespace rsu::ros
