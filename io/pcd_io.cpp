#include "io/pcd_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>

namespace rsu::io {
namespace {

// The fixed layout written by write_pcd; packed, 31 bytes per point.
struct FieldSpec {
  const char* name;
  std::uint8_t datatype;
  std::uint32_t size;
};
constexpr FieldSpec kFields[] = {
    {"x", pcl::PCLPointField::FLOAT32, 4},    {"y", pcl::PCLPointField::FLOAT32, 4},
    {"z", pcl::PCLPointField::FLOAT32, 4},    {"intensity", pcl::PCLPointField::FLOAT32, 4},
    {"ring", pcl::PCLPointField::UINT16, 2},  {"azimuth", pcl::PCLPointField::FLOAT32, 4},
    {"time", pcl::PCLPointField::FLOAT64, 8},
};

template <typename T>
void put(std::uint8_t* dst, T value) {
  std::memcpy(dst, &value, sizeof(T));
}

// Reads one field of any numeric PCD type as double.
double read_as_double(const std::uint8_t* src, std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: {
      std::int8_t v;
      std::memcpy(&v, src, 1);
      return v;
    }
    case pcl::PCLPointField::UINT8: {
      std::uint8_t v;
      std::memcpy(&v, src, 1);
      return v;
    }
    case pcl::PCLPointField::INT16: {
      std::int16_t v;
      std::memcpy(&v, src, 2);
      return v;
    }
    case pcl::PCLPointField::UINT16: {
      std::uint16_t v;
      std::memcpy(&v, src, 2);
      return v;
    }
    case pcl::PCLPointField::INT32: {
      std::int32_t v;
      std::memcpy(&v, src, 4);
      return v;
    }
    case pcl::PCLPointField::UINT32: {
      std::uint32_t v;
      std::memcpy(&v, src, 4);
      return v;
    }
    case pcl::PCLPointField::FLOAT32: {
      float v;
      std::memcpy(&v, src, 4);
      return static_cast<double>(v);
    }
    case pcl::PCLPointField::FLOAT64: {
      double v;
      std::memcpy(&v, src, 8);
      return v;
    }
    default:
      return std::nan("");
  }
}

std::uint32_t datatype_size(std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8:
    case pcl::PCLPointField::UINT8:
      return 1;
    case pcl::PCLPointField::INT16:
    case pcl::PCLPointField::UINT16:
      return 2;
    case pcl::PCLPointField::INT32:
    case pcl::PCLPointField::UINT32:
    case pcl::PCLPointField::FLOAT32:
      return 4;
    case pcl::PCLPointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

}  // namespace

namespace {

// A PCL cloud of `points` with the given packed fields, each point written by `put_point`.
template <typename PutPoint>
void write_fields(const std::string& path, const std::vector<LidarPoint>& points,
                  std::span<const FieldSpec> fields, PutPoint put_point) {
  pcl::PCLPointCloud2 cloud;
  std::uint32_t offset = 0;
  for (const FieldSpec& f : fields) {
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
    put_point(dst, p);
    dst += cloud.point_step;
  }
  pcl::PCDWriter writer;
  if (writer.writeBinary(path, cloud) != 0)
    throw PcdError(path + ": cannot write PCD file");
}

constexpr FieldSpec kRotationFields[] = {
    {"x", pcl::PCLPointField::FLOAT32, 4},   {"y", pcl::PCLPointField::FLOAT32, 4},
    {"z", pcl::PCLPointField::FLOAT32, 4},   {"intensity", pcl::PCLPointField::FLOAT32, 4},
    {"ring", pcl::PCLPointField::UINT16, 2}, {"time", pcl::PCLPointField::UINT32, 4},
};

}  // namespace

void write_pcd(const std::string& path, const std::vector<LidarPoint>& points) {
  write_fields(path, points, kFields, [](std::uint8_t* dst, const LidarPoint& p) {
    put(dst + 0, p.x);
    put(dst + 4, p.y);
    put(dst + 8, p.z);
    put(dst + 12, p.intensity);
    put(dst + 16, p.ring);
    put(dst + 18, p.azimuth_rad);
    put(dst + 22, static_cast<double>(p.time_ns) * 1e-9);
  });
}

void write_rotation_pcd(const std::string& path, const std::vector<LidarPoint>& points,
                        TimeNs rotation_start_ns) {
  for (const LidarPoint& p : points) {
    const TimeNs since = p.time_ns - rotation_start_ns;
    if (since < 0 || since > TimeNs{0xFFFFFFFF})
      throw std::invalid_argument(path + ": a point outside [rotation start, + 4.29 s]");
  }
  write_fields(path, points, kRotationFields, [rotation_start_ns](std::uint8_t* dst, const LidarPoint& p) {
    put(dst + 0, p.x);
    put(dst + 4, p.y);
    put(dst + 8, p.z);
    put(dst + 12, p.intensity);
    put(dst + 16, p.ring);
    put(dst + 18, static_cast<std::uint32_t>(p.time_ns - rotation_start_ns));
  });
}

namespace {

// Parses a header value as a count: digits only, below 2^31 (PCL stores these as int or uint32).
std::optional<std::uint64_t> header_count(const std::string& token) {
  if (token.empty() || token.size() > 10 || token.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const std::uint64_t v = std::stoull(token);
  return v < (std::uint64_t{1} << 31) ? std::optional<std::uint64_t>(v) : std::nullopt;
}

// PCL 1.13's reader trusts the header (found by fuzz/pcd_fuzzer): readHeader() allocates the whole
// cloud the header declares before it reads any data, so a 200-byte file declaring billions of points
// takes gigabytes; a COUNT of -1 wraps its point size, and a FIELDS or COUNT line after POINTS (even
// after DATA: it goes on parsing header lines there) changes the layout after the buffer is sized, so
// the ASCII reader writes outside it; binary_compressed data allocates the size it states. So the
// header is read here first, the way PCL reads it (keyword = a first word starting with it, values
// split on tab, CR and space): keywords once each and in the v0.7 order, counts plain numbers, sizes
// 1, 2, 4 or 8 bytes, points at most 1 MiB, and the declared bytes present in the file (ASCII: a value
// takes at least 2 bytes of text, "0 ", for at most 8 in memory, so at most 4 bytes per byte of file).
void check_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return;  // PCL reports the missing file
  in.seekg(0, std::ios::end);
  const auto file_bytes = static_cast<std::uint64_t>(std::max<std::streamoff>(in.tellg(), 0));
  in.seekg(0);
  auto malformed = [&](const std::string& key) {
    throw PcdError(path + ": malformed PCD header (" + key + ")");
  };
  auto numbers = [&](const std::vector<std::string>& words, const char* key) {
    std::vector<std::uint64_t> out;
    for (std::size_t i = 1; i < words.size(); ++i) {
      const auto v = header_count(words[i]);
      if (!v)
        malformed(key);
      out.push_back(*v);
    }
    return out;
  };
  auto single = [&](const std::vector<std::string>& words, const char* key) {
    const std::vector<std::uint64_t> v = numbers(words, key);
    if (v.size() != 1)
      malformed(key);
    return v[0];
  };
  std::vector<std::uint64_t> sizes, counts;
  std::uint64_t width = 1, height = 1, points = 0, data_begin = 0;
  enum class DataKind { kAscii, kBinary, kCompressed } data_kind = DataKind::kAscii;
  std::size_t fields = 0;
  // The header's keywords in the order PCD v0.7 prescribes. PCL resets the fields when FIELDS comes
  // again and sizes its buffer when it meets POINTS, so a repeated or reordered keyword leaves the
  // buffer smaller than the layout it then fills: each keyword may come once, in this order.
  static constexpr const char* kOrder[] = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                           "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  std::size_t next_rank = 0;
  std::string line;
  while (std::getline(in, line)) {
    // Read like PCL: the line trimmed of white space, the keyword its first word, the values split
    // on tab, CR and space.
    constexpr const char* kSpace = " \t\n\v\f\r";
    const std::size_t first = line.find_first_not_of(kSpace);
    if (first == std::string::npos)
      continue;
    line = line.substr(first, line.find_last_not_of(kSpace) - first + 1);
    std::vector<std::string> words;
    std::size_t begin = 0;
    while (begin <= line.size()) {
      const std::size_t end = std::min(line.find_first_of("\t\r ", begin), line.size());
      if (end > begin)
        words.push_back(line.substr(begin, end - begin));
      begin = end + 1;
    }
    const std::string key = line.substr(0, line.find_first_of(kSpace));
    if (key[0] == '#')
      continue;
    auto is = [&](const char* keyword) { return key.rfind(keyword, 0) == 0; };
    std::size_t rank = std::size(kOrder);
    for (std::size_t r = 0; r < std::size(kOrder); ++r)
      if (is(kOrder[r]) || (r == 1 && is("COLUMNS")))
        rank = r;
    if (rank == std::size(kOrder))
      break;  // PCL ends the header at the first unknown line too
    if (rank < next_rank)
      malformed(std::string(kOrder[rank]) + " repeated or out of order");
    next_rank = rank + 1;
    const char* name = kOrder[rank];
    if (rank == 1) {
      fields = words.size() - 1;
    } else if (rank == 2 || rank == 4) {
      (rank == 2 ? sizes : counts) = numbers(words, name);
      if (words.size() - 1 != fields)
        malformed(std::string(name) + " does not match FIELDS");
    } else if (rank == 3) {
      if (words.size() - 1 != fields)
        malformed("TYPE does not match FIELDS");
    } else if (rank == 5) {
      width = single(words, name);
    } else if (rank == 6) {
      height = single(words, name);
    } else if (rank == 8) {
      points = single(words, name);
    } else if (rank == 9) {
      data_begin = static_cast<std::uint64_t>(std::max<std::streamoff>(in.tellg(), 0));
      if (words.size() > 1 && words[1].rfind("binary_compressed", 0) == 0)
        data_kind = DataKind::kCompressed;
      else if (words.size() > 1 && words[1].rfind("binary", 0) == 0)
        data_kind = DataKind::kBinary;
      // No break: PCL goes on reading header lines after DATA (into the data), so a keyword there
      // would change the layout after the buffer is sized; the order check above refuses it.
    }
  }
  std::uint64_t point_step = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    if (sizes[i] != 1 && sizes[i] != 2 && sizes[i] != 4 && sizes[i] != 8)
      malformed("SIZE");
    const std::uint64_t count = i < counts.size() ? counts[i] : 1;
    if (count == 0 || count > (std::uint64_t{1} << 16))
      malformed("COUNT");
    point_step += sizes[i] * count;  // below 2^19 per field
  }
  if (point_step > (std::uint64_t{1} << 20))
    malformed("SIZE x COUNT: points larger than 1 MiB");
  const std::uint64_t declared_points = std::max(points, width * height);  // below 2^62
  if (point_step == 0 || declared_points > (std::uint64_t{1} << 40) / point_step)
    return;  // nothing to allocate, or PCL refuses it (more than 2^32 bytes do not fit its sizes)
  const std::uint64_t declared_bytes = declared_points * point_step;
  const std::uint64_t data_bytes = file_bytes - std::min(file_bytes, data_begin);
  auto too_large = [&](std::uint64_t room) {
    if (declared_bytes > room)
      throw PcdError(path + ": PCD header declares " + std::to_string(declared_points) + " points of " +
                     std::to_string(point_step) + " bytes, more than the file's " +
                     std::to_string(data_bytes) + " bytes of data can hold");
  };
  switch (data_kind) {
    case DataKind::kAscii:
      too_large(4 * data_bytes);
      break;
    case DataKind::kBinary:
      too_large(data_bytes);
      break;
    case DataKind::kCompressed: {
      // PCL allocates the uncompressed size the data block states, and unpacks every declared point
      // into it, whatever it says: the two must agree, and the compressed block must be in the file.
      std::uint32_t sizes_le[2] = {0, 0};  // compressed, uncompressed; native order, as PCL reads them
      in.clear();
      in.seekg(static_cast<std::streamoff>(data_begin));
      if (data_bytes < 8 || !in.read(reinterpret_cast<char*>(sizes_le), 8))
        malformed("binary_compressed data without its sizes");
      if (sizes_le[0] > data_bytes - 8 || sizes_le[1] != declared_bytes)
        malformed("binary_compressed sizes do not match the header or the file");
      break;
    }
  }
}

// PCL's reader, made to keep read_pcd's promise of PcdError and nothing else on a malformed file.
pcl::PCLPointCloud2 load_cloud(const std::string& path) {
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  try {
    // PCL 1.13's read() dereferences the first field of a header that declares none (an empty file, a
    // header without FIELDS: PCL issue #5854, fixed after 1.13), so the header is checked first.
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int pcd_version = 0;
    int data_type = 0;
    unsigned int data_index = 0;
    check_header(path);
    if (reader.readHeader(path, cloud, origin, orientation, pcd_version, data_type, data_index) != 0)
      throw PcdError(path + ": cannot read PCD file (missing or malformed header)");
    if (cloud.fields.empty())
      throw PcdError(path + ": PCD header declares no fields");
    if (reader.read(path, cloud) != 0)
      throw PcdError(path + ": cannot read PCD file (missing or malformed)");
  } catch (const PcdError&) {
    throw;
  } catch (const std::exception& e) {
    // PCL's header parser indexes tokens with at(): a line such as "DATA'ascii" throws out_of_range.
    throw PcdError(path + ": malformed PCD file (" + e.what() + ")");
  }
  return cloud;
}

}  // namespace

std::vector<LidarPoint> read_pcd(const std::string& path) {
  const pcl::PCLPointCloud2 cloud = load_cloud(path);

  struct Located {
    std::uint32_t offset;
    std::uint8_t datatype;
  };
  auto find = [&](const char* name) -> std::optional<Located> {
    for (const auto& f : cloud.fields) {
      if (f.name == name) {
        const std::uint32_t size = datatype_size(f.datatype);
        if (size == 0)
          throw PcdError(path + ": field \"" + name + "\" has an unsupported type");
        if (f.offset + size > cloud.point_step)
          throw PcdError(path + ": field \"" + name + "\" lies outside the point");
        return Located{f.offset, f.datatype};
      }
    }
    return std::nullopt;
  };
  const auto x = find("x"), y = find("y"), z = find("z");
  if (!x || !y || !z)
    throw PcdError(path + ": PCD has no x, y, z fields");
  const auto intensity = find("intensity"), ring = find("ring"), azimuth = find("azimuth"),
             time = find("time");

  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() < n * cloud.point_step)
    throw PcdError(path + ": PCD data shorter than its header says");
  std::vector<LidarPoint> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* src = cloud.data.data() + i * cloud.point_step;
    LidarPoint p;
    p.x = static_cast<float>(read_as_double(src + x->offset, x->datatype));
    p.y = static_cast<float>(read_as_double(src + y->offset, y->datatype));
    p.z = static_cast<float>(read_as_double(src + z->offset, z->datatype));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      continue;  // organised-cloud holes
    if (intensity)
      p.intensity = static_cast<float>(read_as_double(src + intensity->offset, intensity->datatype));
    if (ring) {
      // Casting a value outside uint16 (or NaN) is undefined behaviour (found by fuzz/pcd_fuzzer).
      const double r = read_as_double(src + ring->offset, ring->datatype);
      if (!(r >= 0.0 && r <= 65535.0))
        throw PcdError(path + ": point " + std::to_string(i) + " has ring " + std::to_string(r) +
                       ", not a ring number");
      p.ring = static_cast<std::uint16_t>(r);
    }
    if (azimuth)
      p.azimuth_rad = static_cast<float>(read_as_double(src + azimuth->offset, azimuth->datatype));
    if (time) {
      // Nanoseconds must fit TimeNs (int64: +-292 years); llround of anything else is meaningless.
      const double t_ns = read_as_double(src + time->offset, time->datatype) * 1e9;
      if (!(std::abs(t_ns) < 9.2e18))
        throw PcdError(path + ": point " + std::to_string(i) + " has time " + std::to_string(t_ns * 1e-9) +
                       " s, outside the clock's range");
      p.time_ns = static_cast<TimeNs>(std::llround(t_ns));
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace rsu::io
