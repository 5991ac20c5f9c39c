// SPDX-License-Identifier: Apache-2.0
// Fuzzes the PointCloud2 layout parser and point decoder (lib/ros/pointcloud2_layout.h): any header,
// field list and data must give a rejection reason or points, never a read out of bounds, undefined
// behaviour or a point that is not finite.
// Input: u8 flags (bit 0 big endian, bit 1 is_dense), u16 width, u8 height, u16 point_step,
// u16 + u16 row_step (low, high), u8 field count (mod 12), per field {u8 name index, u16 offset,
// u8 datatype, u8 count}, then the data bytes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string_view>
#include <vector>

#include "fuzz_input.h"
#include "ros/pointcloud2_layout.h"

namespace {

constexpr std::string_view kNames[] = {"x", "y", "z", "intensity", "ring", "time", "t", "rgb", "", "label"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rsu::fuzz::FuzzInput in(data, size);
  rsu::ros::PointCloud2View cloud;
  const std::uint8_t flags = in.u8();
  cloud.is_bigendian = (flags & 1U) != 0;
  cloud.is_dense = (flags & 2U) != 0;
  cloud.stamp = 1'700'000'000'000'000'000;
  cloud.width = in.u16();
  cloud.height = in.u8();
  cloud.point_step = in.u16();
  cloud.row_step = in.u16();
  cloud.row_step |= static_cast<std::uint32_t>(in.u16()) << 16;
  std::vector<rsu::ros::PointFieldView> fields(in.u8() % 12);
  for (auto& f : fields) {
    f.name = kNames[in.u8() % std::size(kNames)];
    f.offset = in.u16();
    f.datatype = in.u8();
    f.count = in.u8();
  }
  cloud.fields = fields;
  cloud.data = in.take(size);

  const rsu::ros::LayoutResult layout = rsu::ros::parse_layout(cloud);
  if (!layout.ok())
    return 0;
  std::vector<rsu::lidar::LidarPoint> points;
  static constexpr std::uint16_t kRingMap[] = {3, 1, 2, 0};  // bit 2: rings in elevation order
  const std::span<const std::uint16_t> ring_map =
      (flags & 4U) != 0 ? std::span<const std::uint16_t>(kRingMap) : std::span<const std::uint16_t>();
  const auto stats = rsu::ros::decode_points(cloud, layout.layout, ring_map, points);
  const std::uint64_t declared = std::uint64_t{cloud.width} * cloud.height;
  if (stats.points != points.size() ||
      stats.points + stats.non_finite_skipped + stats.bad_ring_skipped + stats.bad_time_skipped != declared)
    std::abort();
  for (const rsu::lidar::LidarPoint& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !(p.azimuth_rad >= 0.0F) ||
        !(p.azimuth_rad < 6.2832F))
      std::abort();
  }
  return 0;
}
