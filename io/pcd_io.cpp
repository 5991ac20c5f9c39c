#include "io/pcd_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <cstring>
#include <optional>

namespace rsu::io {
namespace {

// The fixed layout written by write_pcd; packed, 31 bytes per point.
struct FieldSpec {
  const char* name;
  std::uint8_t datatype;
  std::uint32_t size;
};
constexpr FieldSpec kFields[] = {
    {"x", pcl::PCLPointField::FLOAT32, 4},         {"y", pcl::PCLPointField::FLOAT32, 4},
    {"z", pcl::PCLPointField::FLOAT32, 4},         {"intensity", pcl::PCLPointField::FLOAT32, 4},
    {"ring", pcl::PCLPointField::UINT16, 2},       {"azimuth", pcl::PCLPointField::FLOAT32, 4},
    {"time", pcl::PCLPointField::FLOAT64, 8},
};

template <typename T>
void put(std::uint8_t* dst, T value) {
  std::memcpy(dst, &value, sizeof(T));
}

// Reads one field of any numeric PCD type as double.
double read_as_double(const std::uint8_t* src, std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: { std::int8_t v; std::memcpy(&v, src, 1); return v; }
    case pcl::PCLPointField::UINT8: { std::uint8_t v; std::memcpy(&v, src, 1); return v; }
    case pcl::PCLPointField::INT16: { std::int16_t v; std::memcpy(&v, src, 2); return v; }
    case pcl::PCLPointField::UINT16: { std::uint16_t v; std::memcpy(&v, src, 2); return v; }
    case pcl::PCLPointField::INT32: { std::int32_t v; std::memcpy(&v, src, 4); return v; }
    case pcl::PCLPointField::UINT32: { std::uint32_t v; std::memcpy(&v, src, 4); return v; }
    case pcl::PCLPointField::FLOAT32: { float v; std::memcpy(&v, src, 4); return v; }
    case pcl::PCLPointField::FLOAT64: { double v; std::memcpy(&v, src, 8); return v; }
    default: return std::nan("");
  }
}

std::uint32_t datatype_size(std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: case pcl::PCLPointField::UINT8: return 1;
    case pcl::PCLPointField::INT16: case pcl::PCLPointField::UINT16: return 2;
    case pcl::PCLPointField::INT32: case pcl::PCLPointField::UINT32: case pcl::PCLPointField::FLOAT32: return 4;
    case pcl::PCLPointField::FLOAT64: return 8;
    default: return 0;
  }
}

}  // namespace

void write_pcd(const std::string& path, const std::vector<LidarPoint>& points) {
  pcl::PCLPointCloud2 cloud;
  std::uint32_t offset = 0;
  for (const FieldSpec& f : kFields) {
    pcl::PCLPointField field;
    field.name = f.name;
    field.offset = offset;
    field.datatype = f.datatype;
    field.count = 1;
    cloud.fields.push_back(field);
    offset += f.size;
  }
  cloud.point_step = offset;
  cloud.width = static_cast<std::uint32_t>(points.size());
  cloud.height = 1;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = true;
  cloud.data.resize(static_cast<std::size_t>(cloud.row_step));
  std::uint8_t* dst = cloud.data.data();
  for (const LidarPoint& p : points) {
    put(dst + 0, p.x);
    put(dst + 4, p.y);
    put(dst + 8, p.z);
    put(dst + 12, p.intensity);
    put(dst + 16, p.ring);
    put(dst + 18, p.azimuth_rad);
    put(dst + 22, static_cast<double>(p.time_ns) * 1e-9);
    dst += cloud.point_step;
  }
  pcl::PCDWriter writer;
  if (writer.writeBinary(path, cloud) != 0) throw PcdError(path + ": cannot write PCD file");
}

std::vector<LidarPoint> read_pcd(const std::string& path) {
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  if (reader.read(path, cloud) != 0) throw PcdError(path + ": cannot read PCD file (missing or malformed)");

  struct Located {
    std::uint32_t offset;
    std::uint8_t datatype;
  };
  auto find = [&](const char* name) -> std::optional<Located> {
    for (const auto& f : cloud.fields) {
      if (f.name == name) {
        const std::uint32_t size = datatype_size(f.datatype);
        if (size == 0) throw PcdError(path + ": field \"" + name + "\" has an unsupported type");
        if (f.offset + size > cloud.point_step) throw PcdError(path + ": field \"" + name + "\" lies outside the point");
        return Located{f.offset, f.datatype};
      }
    }
    return std::nullopt;
  };
  const auto x = find("x"), y = find("y"), z = find("z");
  if (!x || !y || !z) throw PcdError(path + ": PCD has no x, y, z fields");
  const auto intensity = find("intensity"), ring = find("ring"), azimuth = find("azimuth"), time = find("time");

  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() < n * cloud.point_step) throw PcdError(path + ": PCD data shorter than its header says");
  std::vector<LidarPoint> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* src = cloud.data.data() + i * cloud.point_step;
    LidarPoint p;
    p.x = static_cast<float>(read_as_double(src + x->offset, x->datatype));
    p.y = static_cast<float>(read_as_double(src + y->offset, y->datatype));
    p.z = static_cast<float>(read_as_double(src + z->offset, z->datatype));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;  // organised-cloud holes
    if (intensity) p.intensity = static_cast<float>(read_as_double(src + intensity->offset, intensity->datatype));
    if (ring) p.ring = static_cast<std::uint16_t>(read_as_double(src + ring->offset, ring->datatype));
    if (azimuth) p.azimuth_rad = static_cast<float>(read_as_double(src + azimuth->offset, azimuth->datatype));
    if (time) p.time_ns = static_cast<TimeNs>(std::llround(read_as_double(src + time->offset, time->datatype) * 1e9));
    out.push_back(p);
  }
  return out;
}

}  // namespace rsu::io
