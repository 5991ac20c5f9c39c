// SPDX-License-Identifier: Apache-2.0
// The byte layout of Ouster lidar packets (UDP payloads, port 7502 by default), per profile, from the
// OS0/OS1/OS2 firmware user manuals ("Lidar Data Format") and the public Ouster SDK. Little-endian.
//
// LEGACY: no packet header or footer; each column is
//     timestamp u64 (ns) | measurement id u16 | frame id u16 | encoder count u32      (16 bytes)
//     pixels_per_column x { range u32 (low 20 bits, mm) | reflectivity u16 | signal u16 | near-IR u16 | 2
//     unused } status u32 (0xFFFFFFFF valid, 0 not)
// Others ("eUDP"): a 32-byte packet header
//     packet type u16 (1 = lidar) | frame id u16 | initialization id u24 | serial number u40 | ...
//   then each column is  timestamp u64 | measurement id u16 | status u16 (bit 0: valid)   (12 bytes)
//   and its pixels, then a 32-byte packet footer:
//     RNG19_RFL8_SIG16_NIR16, 12 bytes: range u32 (low 19 bits, mm) | reflectivity u8 | 1 | signal u16 |
//     near-IR u16 | 2 RNG15_RFL8_NIR8, 4 bytes:         range u16 (low 15 bits, 8 mm units) | reflectivity u8
//     | near-IR u8 (/16)
// The measurement id is the column's place in the rotation, 0 .. columns_per_frame - 1; the frame id
// counts rotations (mod 2^16). A range of 0 means no return.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "common/byte_order.h"
#include "lidar/ouster/ouster_metadata.h"

namespace rsu::lidar::ouster {

constexpr std::size_t kMaxUdpPayload = 65507;
constexpr std::size_t kImuPacketBytes = 48;  // the LEGACY IMU packet (port 7503 by default)
constexpr std::uint16_t kLidarPacketType = 1;

struct PacketLayout {
  std::size_t packet_header_bytes = 0;
  std::size_t column_header_bytes = 0;
  std::size_t pixel_bytes = 0;
  std::size_t column_footer_bytes = 0;
  std::size_t packet_footer_bytes = 0;
  std::size_t column_bytes = 0;
  std::size_t packet_bytes = 0;
};
PacketLayout packet_layout(UdpProfile profile, int pixels_per_column, int columns_per_packet);

// eUDP packet header fields; all 0 for LEGACY packets, which have none.
struct PacketHeader {
  std::uint16_t packet_type = 0;
  std::uint16_t frame_id = 0;
  std::uint32_t initialization_id = 0;
  std::uint64_t serial_number = 0;
};

struct ColumnHeader {
  std::uint64_t timestamp_ns = 0;
  std::uint16_t measurement_id = 0;
  std::uint16_t frame_id = 0;  // LEGACY: the column's own; eUDP: the packet header's
  std::uint32_t status = 0;
  bool valid() const { return (status & 1U) != 0; }
};

// One pixel, in common units whatever the profile.
struct Pixel {
  std::uint32_t range_mm = 0;  // 0 = no return
  std::uint16_t reflectivity = 0;
  std::uint16_t signal = 0;  // 0 in RNG15_RFL8_NIR8, which has none
  std::uint16_t near_ir = 0;
};

// Reads the fields of one packet whose size the caller has checked against the layout.
class PacketReader {
 public:
  PacketReader(UdpProfile profile, int pixels_per_column, int columns_per_packet);

  const PacketLayout& layout() const { return layout_; }
  PacketHeader header(std::span<const std::uint8_t> packet) const;
  ColumnHeader column(std::span<const std::uint8_t> packet, int column) const;
  // Defined here, not in the .cpp: the decoder reads every pixel of a 128 x 2048 x 20 Hz stream
  // (5.2 M a second), and a call per pixel was a third of its time.
  Pixel pixel(std::span<const std::uint8_t> packet, int column, int row) const;

 private:
  std::size_t column_offset(int column) const {
    return layout_.packet_header_bytes + static_cast<std::size_t>(column) * layout_.column_bytes;
  }

  static constexpr std::uint32_t kRange20Mask = 0x000FFFFFU;
  static constexpr std::uint32_t kRange19Mask = 0x0007FFFFU;
  static constexpr std::uint32_t kRange15Mask = 0x7FFFU;
  static constexpr std::uint32_t kRange15UnitMm = 8;  // RNG15: the SDK shifts the 15-bit range left by 3
  static constexpr std::uint16_t kNearIr8Scale = 16;  // RNG15_RFL8_NIR8: the SDK scales its near-IR by 16

  UdpProfile profile_;
  PacketLayout layout_;
};

inline Pixel PacketReader::pixel(std::span<const std::uint8_t> packet, int column, int row) const {
  const std::size_t at = column_offset(column) + layout_.column_header_bytes +
                         static_cast<std::size_t>(row) * layout_.pixel_bytes;
  Pixel p;
  switch (profile_) {
    case UdpProfile::legacy:
      p.range_mm = load_le<std::uint32_t>(packet, at) & kRange20Mask;
      p.reflectivity = load_le<std::uint16_t>(packet, at + 4);
      p.signal = load_le<std::uint16_t>(packet, at + 6);
      p.near_ir = load_le<std::uint16_t>(packet, at + 8);
      break;
    case UdpProfile::rng19_rfl8_sig16_nir16:
      p.range_mm = load_le<std::uint32_t>(packet, at) & kRange19Mask;
      p.reflectivity = packet[at + 4];
      p.signal = load_le<std::uint16_t>(packet, at + 6);
      p.near_ir = load_le<std::uint16_t>(packet, at + 8);
      break;
    case UdpProfile::rng15_rfl8_nir8:
      p.range_mm = (load_le<std::uint16_t>(packet, at) & kRange15Mask) * kRange15UnitMm;
      p.reflectivity = packet[at + 2];
      p.near_ir = static_cast<std::uint16_t>(packet[at + 3] * kNearIr8Scale);
      break;
  }
  return p;
}

}  // namespace rsu::lidar::ouster
