// SPDX-License-Identifier: Apache-2.0
// Ouster lidar packets built by hand for tests, straight from the firmware user manual's layout
// (independent of lib/lidar/ouster's reader), and a raw reader of real packets for counting what a
// capture must decode to.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "lidar/ouster/ouster_metadata.h"

namespace rsu::lidar::ouster::test {

inline void put(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) {
    b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
  }
}

inline std::uint64_t get(std::span<const std::uint8_t> b, std::size_t at, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) {
    v |= static_cast<std::uint64_t>(b[at + static_cast<std::size_t>(i)]) << (8 * i);
  }
  return v;
}

// Sizes per the manual: LEGACY columns 16 + 12 per pixel + 4; eUDP 32-byte header and footer,
// columns 12 + 12 (RNG19) or 4 (RNG15) per pixel.
struct TestLayout {
  bool legacy;
  std::size_t header, column, pixel, packet;
};

inline TestLayout test_layout(const Metadata& m) {
  const bool legacy = m.profile == UdpProfile::legacy;
  const std::size_t pixel = m.profile == UdpProfile::rng15_rfl8_nir8 ? 4 : 12;
  const std::size_t column = (legacy ? 20 : 12) + pixel * static_cast<std::size_t>(m.pixels_per_column);
  const std::size_t header = legacy ? 0 : 32;
  return {legacy, header, column, pixel,
          header + column * static_cast<std::size_t>(m.columns_per_packet) + (legacy ? 0 : 32)};
}

// One packet of `m`'s format: columns first_column.. of frame `frame_id`, all valid, column c's
// timestamp t0 + c * dt, every range 0 until set_range.
class PacketBuilder {
 public:
  PacketBuilder(const Metadata& m, std::uint16_t frame_id, int first_column, std::uint64_t t0_ns,
                std::uint64_t dt_ns)
      : m_(m), l_(test_layout(m)), bytes_(l_.packet, 0) {
    if (!l_.legacy) {
      put(bytes_, 0, 1, 2);  // lidar packet
      put(bytes_, 2, frame_id, 2);
      put(bytes_, 4, m.initialization_id.value_or(0), 3);
      put(bytes_, 7, m.serial_number.value_or(0), 5);
    }
    for (int c = 0; c < m.columns_per_packet; ++c) {
      const std::size_t at = column_at(c);
      put(bytes_, at, t0_ns + static_cast<std::uint64_t>(c) * dt_ns, 8);
      put(bytes_, at + 8, static_cast<std::uint64_t>(first_column + c), 2);
      if (l_.legacy) {
        put(bytes_, at + 10, frame_id, 2);
        put(bytes_, at + l_.column - 4, 0xFFFFFFFFU, 4);
      } else {
        put(bytes_, at + 10, 1, 2);
      }
    }
  }

  std::size_t column_at(int c) const { return l_.header + static_cast<std::size_t>(c) * l_.column; }
  std::size_t pixel_at(int c, int row) const {
    return column_at(c) + (l_.legacy ? 16 : 12) + static_cast<std::size_t>(row) * l_.pixel;
  }

  // Range in mm (RNG15: must be a multiple of 8), reflectivity byte; `flag_bits` set above the range field.
  void set_range(int c, int row, std::uint32_t range_mm, std::uint8_t reflectivity = 100,
                 bool flag_bits = false) {
    const std::size_t at = pixel_at(c, row);
    if (m_.profile == UdpProfile::rng15_rfl8_nir8) {
      put(bytes_, at, (range_mm / 8) | (flag_bits ? 0x8000U : 0U), 2);
      bytes_[at + 2] = reflectivity;
    } else {
      const std::uint32_t high =
          flag_bits ? (m_.profile == UdpProfile::legacy ? 0xFFF00000U : 0xFFF80000U) : 0U;
      put(bytes_, at, range_mm | high, 4);
      if (m_.profile == UdpProfile::legacy) {
        put(bytes_, at + 4, reflectivity, 2);
      } else {
        bytes_[at + 4] = reflectivity;
      }
    }
  }
  void set_invalid(int c) {
    if (l_.legacy) {
      put(bytes_, column_at(c) + l_.column - 4, 0, 4);
    } else {
      put(bytes_, column_at(c) + 10, 0, 2);
    }
  }
  void set_measurement_id(int c, std::uint16_t id) { put(bytes_, column_at(c) + 8, id, 2); }
  void set_column_frame_id(int c, std::uint16_t id) { put(bytes_, column_at(c) + 10, id, 2); }
  void set_timestamp(int c, std::uint64_t t) { put(bytes_, column_at(c), t, 8); }

  std::vector<std::uint8_t>& bytes() { return bytes_; }

 private:
  const Metadata& m_;
  TestLayout l_;
  std::vector<std::uint8_t> bytes_;
};

// A column of a real packet, read by the manual's layout.
struct RawColumn {
  std::uint64_t timestamp_ns;
  int measurement_id;
  int frame_id;
  bool valid;
  std::vector<std::uint32_t> range_mm;  // per row
};

inline std::vector<RawColumn> raw_columns(const Metadata& m, std::span<const std::uint8_t> packet) {
  const TestLayout l = test_layout(m);
  std::vector<RawColumn> out;
  for (int c = 0; c < m.columns_per_packet; ++c) {
    const std::size_t at = l.header + static_cast<std::size_t>(c) * l.column;
    RawColumn col;
    col.timestamp_ns = get(packet, at, 8);
    col.measurement_id = static_cast<int>(get(packet, at + 8, 2));
    col.frame_id = static_cast<int>(l.legacy ? get(packet, at + 10, 2) : get(packet, 2, 2));
    col.valid = (l.legacy ? get(packet, at + l.column - 4, 4) : get(packet, at + 10, 2)) & 1U;
    for (int r = 0; r < m.pixels_per_column; ++r) {
      const std::size_t px = at + (l.legacy ? 16 : 12) + static_cast<std::size_t>(r) * l.pixel;
      std::uint32_t range = 0;
      if (m.profile == UdpProfile::legacy) {
        range = static_cast<std::uint32_t>(get(packet, px, 4)) & 0xFFFFFU;
      } else if (m.profile == UdpProfile::rng19_rfl8_sig16_nir16) {
        range = static_cast<std::uint32_t>(get(packet, px, 4)) & 0x7FFFFU;
      } else {
        range = (static_cast<std::uint32_t>(get(packet, px, 2)) & 0x7FFFU) * 8U;
      }
      col.range_mm.push_back(range);
    }
    out.push_back(std::move(col));
  }
  return out;
}

}  // namespace rsu::lidar::ouster::test
