// SPDX-License-Identifier: Apache-2.0
// Builds PointCloud2 byte layouts for the tests by hand: every value is written byte by byte from its
// integer representation in the requested byte order (shifts, not memcpy), independently of how
// lib/ros reads them.
#pragma once

#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "ros/pointcloud2_layout.h"

namespace rsu::ros::test {

struct FieldSpec {
  std::string name;
  std::uint8_t datatype;
  std::uint32_t count = 1;
};

// Writes `bits` (the value's representation, `size` bytes) at `at` in big or little endian order.
inline void put_bits(std::vector<std::uint8_t>& data, std::size_t at, std::uint64_t bits, std::uint32_t size,
                     bool big_endian) {
  for (std::uint32_t i = 0; i < size; ++i) {
    const std::uint32_t shift = 8 * (big_endian ? size - 1 - i : i);
    data[at + i] = static_cast<std::uint8_t>((bits >> shift) & 0xFFU);
  }
}

// The representation of `value` as `datatype` (value must be representable).
inline std::uint64_t bits_of(double value, std::uint8_t datatype) {
  switch (datatype) {
    case 1:
      return static_cast<std::uint8_t>(static_cast<std::int8_t>(value));
    case 2:
      return static_cast<std::uint8_t>(value);
    case 3:
      return static_cast<std::uint16_t>(static_cast<std::int16_t>(value));
    case 4:
      return static_cast<std::uint16_t>(value);
    case 5:
      return static_cast<std::uint32_t>(static_cast<std::int32_t>(value));
    case 6:
      return static_cast<std::uint32_t>(value);
    case 7:
      return std::bit_cast<std::uint32_t>(static_cast<float>(value));
    default:
      return std::bit_cast<std::uint64_t>(value);
  }
}

inline std::uint32_t size_of(std::uint8_t datatype) {
  constexpr std::uint32_t kSizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
  return datatype <= 8 ? kSizes[datatype] : 0;
}

// A cloud whose fields are packed in order, each aligned to its own size, plus `padding` bytes per
// point and `row_padding` bytes per row. values[point][field] fills the first element of each field.
// Tests may edit the members (fields, steps, data) to break the layout; view() reads them as they are.
struct BuiltCloud {
  std::vector<std::string> names;
  std::vector<PointFieldView> fields;  // names filled in by view()
  std::vector<std::uint8_t> data;
  TimeNs stamp = 0;
  std::uint32_t height = 0, width = 0, point_step = 0, row_step = 0;
  bool big_endian = false;

  PointCloud2View view() {
    for (std::size_t i = 0; i < fields.size() && i < names.size(); ++i)
      fields[i].name = names[i];
    PointCloud2View v;
    v.stamp = stamp;
    v.height = height;
    v.width = width;
    v.fields = fields;
    v.is_bigendian = big_endian;
    v.point_step = point_step;
    v.row_step = row_step;
    v.data = data;
    v.is_dense = true;
    return v;
  }
};

inline BuiltCloud build_cloud(const std::vector<FieldSpec>& specs,
                              const std::vector<std::vector<double>>& values, bool big_endian,
                              std::uint32_t height = 1, std::uint32_t padding = 0,
                              std::uint32_t row_padding = 0, TimeNs stamp = 0) {
  BuiltCloud c;
  std::uint32_t offset = 0;
  for (const FieldSpec& s : specs) {
    const std::uint32_t size = size_of(s.datatype);
    offset = (offset + size - 1) / size * size;
    c.names.push_back(s.name);
    c.fields.push_back({{}, offset, s.datatype, s.count});
    offset += size * s.count;
  }
  c.point_step = offset + padding;
  c.height = height;
  c.width = static_cast<std::uint32_t>(values.size() / height);
  c.row_step = c.width * c.point_step + row_padding;
  c.big_endian = big_endian;
  c.stamp = stamp;
  c.data.assign(std::size_t{c.row_step} * height, 0xAB);
  for (std::size_t p = 0; p < values.size(); ++p) {
    const std::size_t row = p / c.width, col = p % c.width;
    const std::size_t base = row * c.row_step + col * c.point_step;
    for (std::size_t f = 0; f < specs.size(); ++f)
      put_bits(c.data, base + c.fields[f].offset, bits_of(values[p][f], specs[f].datatype),
               size_of(specs[f].datatype), big_endian);
  }
  return c;
}

}  // namespace rsu::ros::test
