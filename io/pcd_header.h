// SPDX-License-Identifier: Apache-2.0
// The header of a PCD file (PCL's Point Cloud Data format, v0.7), read strictly: the keywords VERSION,
// FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS and DATA in that order, each at most once
// (FIELDS, SIZE, TYPE, POINTS and DATA required; COUNT 1, HEIGHT 1 and WIDTH = POINTS by default),
// '#' lines are comments. Every number is checked before anything is sized by it: counts are plain
// decimals below 2^31, sizes 1, 2, 4 or 8 bytes (F: 4 or 8), at most 65536 values per field and 1 MiB
// per point, and WIDTH x HEIGHT = POINTS. (PCL's own reader trusts the header: fuzz/pcd_fuzzer found a
// 200-byte file that made it allocate gigabytes, and layouts changed after its buffer was sized.)
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rsu::io {

struct PcdField {
  std::string name;
  std::uint32_t size = 4;    // bytes per value: 1, 2, 4 or 8
  char type = 'F';           // I signed, U unsigned, F floating point
  std::uint32_t count = 1;   // values per point
  std::uint32_t offset = 0;  // of its first value within a point (binary layout)
};

enum class PcdData { ascii, binary, binary_compressed };

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0;
  std::uint64_t height = 1;
  std::uint64_t points = 0;
  PcdData data = PcdData::ascii;
  std::uint32_t point_step = 0;  // bytes per point, the fields packed in order
  std::size_t data_offset = 0;   // where the data starts in the file

  // The field named `name`, or nullptr.
  const PcdField* find(std::string_view name) const;
};

// The header at the start of `file` (the whole file's bytes). Throws PcdError with what is wrong (the
// caller adds the path).
PcdHeader parse_pcd_header(std::string_view file);

// The header text for `fields` (offsets ignored), `points` points in one row, binary data.
std::string pcd_header_text(const std::vector<PcdField>& fields, std::size_t points);

}  // namespace rsu::io
