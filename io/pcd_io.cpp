// SPDX-License-Identifier: Apache-2.0
#include "io/pcd_io.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>

#include "io/lzf.h"
#include "io/pcd_header.h"

namespace rsu::io {
namespace {

// The layout write_pcd writes: packed, 30 bytes per point.
const std::vector<PcdField> kFields = {
    {"x", 4, 'F'},    {"y", 4, 'F'},       {"z", 4, 'F'},    {"intensity", 4, 'F'},
    {"ring", 2, 'U'}, {"azimuth", 4, 'F'}, {"time", 8, 'F'},
};
// write_rotation_pcd's: time as uint32 ns since the rotation's start.
const std::vector<PcdField> kRotationFields = {
    {"x", 4, 'F'}, {"y", 4, 'F'}, {"z", 4, 'F'}, {"intensity", 4, 'F'}, {"ring", 2, 'U'}, {"time", 4, 'U'},
};

template <typename T>
void put(std::uint8_t* dst, T value) {
  std::memcpy(dst, &value, sizeof(T));
}

template <typename T>
double get(const std::uint8_t* src) {
  T v;
  std::memcpy(&v, src, sizeof(T));
  return static_cast<double>(v);
}

// The first value of field `f` of the point at `src` (binary layout), as double.
double binary_value(const std::uint8_t* src, const PcdField& f) {
  src += f.offset;
  switch (f.type) {
    case 'F':
      return f.size == 4 ? get<float>(src) : get<double>(src);
    case 'I':
      return f.size == 1   ? get<std::int8_t>(src)
             : f.size == 2 ? get<std::int16_t>(src)
             : f.size == 4 ? get<std::int32_t>(src)
                           : get<std::int64_t>(src);
    default:
      return f.size == 1   ? get<std::uint8_t>(src)
             : f.size == 2 ? get<std::uint16_t>(src)
             : f.size == 4 ? get<std::uint32_t>(src)
                           : get<std::uint64_t>(src);
  }
}

// Points of `fields` written by `put_point`, after the header, to `path`.
template <typename PutPoint>
void write_fields(const std::string& path, const std::vector<lidar::LidarPoint>& points,
                  const std::vector<PcdField>& fields, PutPoint put_point) {
  std::uint32_t step = 0;
  for (const PcdField& f : fields)
    step += f.size * f.count;
  std::vector<std::uint8_t> data(points.size() * step);
  for (std::size_t i = 0; i < points.size(); ++i)
    put_point(data.data() + i * step, points[i]);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  const std::string header = pcd_header_text(fields, points.size());
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
  if (!out)
    throw PcdError(path + ": cannot write PCD file");
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw PcdError(path + ": cannot open PCD file");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad())
    throw PcdError(path + ": cannot read PCD file");
  return std::move(bytes).str();
}

// The binary point data (point after point), from binary or binary_compressed data.
std::vector<std::uint8_t> binary_points(const PcdHeader& h, std::string_view data) {
  const std::uint64_t bytes = h.points * h.point_step;
  if (h.data == PcdData::binary) {
    if (data.size() < bytes)
      throw PcdError("PCD header declares " + std::to_string(h.points) + " points of " +
                     std::to_string(h.point_step) + " bytes, more than the file's " +
                     std::to_string(data.size()) + " bytes of data hold");
    return {data.begin(), data.begin() + static_cast<std::ptrdiff_t>(bytes)};
  }
  // binary_compressed: compressed and uncompressed size (uint32 LE), LZF data of the fields one after
  // the other (all points' x, then all y, ...).
  std::uint32_t sizes[2] = {0, 0};
  if (data.size() < sizeof(sizes))
    throw PcdError("binary_compressed data without its sizes");
  std::memcpy(sizes, data.data(), sizeof(sizes));
  if (sizes[0] > data.size() - sizeof(sizes) || sizes[1] != bytes)
    throw PcdError("binary_compressed sizes do not match the header or the file");
  const auto* compressed = reinterpret_cast<const std::uint8_t*>(data.data()) + sizeof(sizes);
  const std::optional<std::vector<std::uint8_t>> by_field = lzf_decompress({compressed, sizes[0]}, bytes);
  if (!by_field)
    throw PcdError("binary_compressed data does not unpack to the declared points");
  std::vector<std::uint8_t> out(bytes);
  std::size_t from = 0;
  for (const PcdField& f : h.fields) {
    const std::size_t field_bytes = std::size_t{f.size} * f.count;
    for (std::size_t i = 0; i < h.points; ++i, from += field_bytes)
      std::memcpy(out.data() + i * h.point_step + f.offset, by_field->data() + from, field_bytes);
  }
  return out;
}

// ASCII data: one line per point, every value of every field.
std::vector<std::vector<double>> ascii_points(const PcdHeader& h, std::string_view data) {
  std::size_t values = 0;
  for (const PcdField& f : h.fields)
    values += f.count;
  std::vector<std::vector<double>> out;
  out.reserve(std::min<std::size_t>(h.points, data.size() / 2));  // a value takes at least "0 "
  std::size_t pos = 0;
  while (out.size() < h.points) {
    if (pos >= data.size())
      throw PcdError("PCD data ends after " + std::to_string(out.size()) + " of " + std::to_string(h.points) +
                     " points");
    const std::size_t eol = std::min(data.find('\n', pos), data.size());
    std::string_view line = data.substr(pos, eol - pos);
    pos = eol + 1;
    std::vector<double> row;
    while (!line.empty()) {
      const std::size_t start = line.find_first_not_of(" \t\r");
      if (start == std::string_view::npos)
        break;
      line.remove_prefix(start);
      double v = 0.0;
      const auto [end, ec] = std::from_chars(line.data(), line.data() + line.size(), v);
      if (ec == std::errc::invalid_argument ||
          (end != line.data() + line.size() && *end != ' ' && *end != '\t' && *end != '\r'))
        throw PcdError("point " + std::to_string(out.size()) + ": not a number in \"" + std::string(line) +
                       "\"");
      row.push_back(ec == std::errc::result_out_of_range ? std::nan("") : v);
      line.remove_prefix(static_cast<std::size_t>(end - line.data()));
    }
    if (row.empty())
      continue;  // blank line
    if (row.size() != values)
      throw PcdError("point " + std::to_string(out.size()) + " has " + std::to_string(row.size()) +
                     " values, the header " + std::to_string(values));
    out.push_back(std::move(row));
  }
  return out;
}

// The fields read_pcd uses, each with its first value's column in an ASCII row.
struct Columns {
  const PcdField* x = nullptr;
  const PcdField* y = nullptr;
  const PcdField* z = nullptr;
  const PcdField* intensity = nullptr;
  const PcdField* ring = nullptr;
  const PcdField* azimuth = nullptr;
  const PcdField* time = nullptr;

  explicit Columns(const PcdHeader& h)
      : x(h.find("x")),
        y(h.find("y")),
        z(h.find("z")),
        intensity(h.find("intensity")),
        ring(h.find("ring")),
        azimuth(h.find("azimuth")),
        time(h.find("time")) {
    if (x == nullptr || y == nullptr || z == nullptr)
      throw PcdError("PCD has no x, y, z fields");
  }
};

// Point `i` from `value(field)`; false for an organised cloud's hole (non-finite x, y or z).
template <typename Value>
bool to_point(std::size_t i, const Columns& c, Value value, lidar::LidarPoint& p) {
  p.x = static_cast<float>(value(*c.x));
  p.y = static_cast<float>(value(*c.y));
  p.z = static_cast<float>(value(*c.z));
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
    return false;
  if (c.intensity)
    p.intensity = static_cast<float>(value(*c.intensity));
  if (c.ring) {
    // Casting a value outside uint16 (or NaN) is undefined behaviour (found by fuzz/pcd_fuzzer).
    const double r = value(*c.ring);
    if (!(r >= 0.0 && r <= 65535.0))
      throw PcdError("point " + std::to_string(i) + " has ring " + std::to_string(r) + ", not a ring number");
    p.ring = static_cast<std::uint16_t>(r);
  }
  if (c.azimuth)
    p.azimuth_rad = static_cast<float>(value(*c.azimuth));
  if (c.time) {
    // Nanoseconds must fit TimeNs (int64: +-292 years); llround of anything else is meaningless.
    const double t_ns = value(*c.time) * 1e9;
    if (!(std::abs(t_ns) < 9.2e18))
      throw PcdError("point " + std::to_string(i) + " has time " + std::to_string(t_ns * 1e-9) +
                     " s, outside the clock's range");
    p.time_ns = static_cast<TimeNs>(std::llround(t_ns));
  }
  return true;
}

std::vector<lidar::LidarPoint> read_points(const std::string& file) {
  const PcdHeader h = parse_pcd_header(file);
  const Columns columns(h);
  const std::string_view data = std::string_view(file).substr(h.data_offset);
  std::vector<lidar::LidarPoint> out;
  lidar::LidarPoint p;
  if (h.data == PcdData::ascii) {
    std::vector<std::size_t> column_of(h.fields.size());
    for (std::size_t f = 1; f < h.fields.size(); ++f)
      column_of[f] = column_of[f - 1] + h.fields[f - 1].count;
    const std::vector<std::vector<double>> rows = ascii_points(h, data);
    out.reserve(rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      auto value = [&](const PcdField& f) {
        return rows[i][column_of[static_cast<std::size_t>(&f - h.fields.data())]];
      };
      if (to_point(i, columns, value, p))
        out.push_back(p);
    }
    return out;
  }
  const std::vector<std::uint8_t> bytes = binary_points(h, data);
  out.reserve(h.points);
  for (std::size_t i = 0; i < h.points; ++i) {
    const std::uint8_t* src = bytes.data() + i * h.point_step;
    if (to_point(
            i, columns, [src](const PcdField& f) { return binary_value(src, f); }, p))
      out.push_back(p);
  }
  return out;
}

}  // namespace

void write_pcd(const std::string& path, const std::vector<lidar::LidarPoint>& points) {
  write_fields(path, points, kFields, [](std::uint8_t* dst, const lidar::LidarPoint& p) {
    put(dst + 0, p.x);
    put(dst + 4, p.y);
    put(dst + 8, p.z);
    put(dst + 12, p.intensity);
    put(dst + 16, p.ring);
    put(dst + 18, p.azimuth_rad);
    put(dst + 22, static_cast<double>(p.time_ns) * 1e-9);
  });
}

void write_rotation_pcd(const std::string& path, const std::vector<lidar::LidarPoint>& points,
                        TimeNs rotation_start_ns) {
  for (const lidar::LidarPoint& p : points) {
    const TimeNs since = p.time_ns - rotation_start_ns;
    if (since < 0 || since > TimeNs{0xFFFFFFFF})
      throw std::invalid_argument(path + ": a point outside [rotation start, + 4.29 s]");
  }
  write_fields(path, points, kRotationFields,
               [rotation_start_ns](std::uint8_t* dst, const lidar::LidarPoint& p) {
                 put(dst + 0, p.x);
                 put(dst + 4, p.y);
                 put(dst + 8, p.z);
                 put(dst + 12, p.intensity);
                 put(dst + 16, p.ring);
                 put(dst + 18, static_cast<std::uint32_t>(p.time_ns - rotation_start_ns));
               });
}

std::vector<lidar::LidarPoint> read_pcd(const std::string& path) {
  const std::string file = read_file(path);
  try {
    return read_points(file);
  } catch (const PcdError& e) {
    throw PcdError(path + ": " + e.what());
  }
}

}  // namespace rsu::io
