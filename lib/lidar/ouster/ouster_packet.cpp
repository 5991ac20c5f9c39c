// SPDX-License-Identifier: Apache-2.0
// Ouster lidar packet layout (see ouster_packet.h).
#include "lidar/ouster/ouster_packet.h"

#include "common/byte_order.h"

namespace rsu::lidar::ouster {
namespace {

// LEGACY column header: timestamp, measurement id, frame id, encoder count.
constexpr std::size_t kLegacyColumnHeader = 16;
constexpr std::size_t kLegacyFrameIdOffset = 10;
constexpr std::size_t kLegacyStatusBytes = 4;
// eUDP: packet header and footer, column header (timestamp, measurement id, status).
constexpr std::size_t kEudpPacketHeader = 32;
constexpr std::size_t kEudpPacketFooter = 32;
constexpr std::size_t kEudpColumnHeader = 12;
constexpr std::size_t kEudpStatusOffset = 10;
constexpr std::size_t kMeasurementIdOffset = 8;

constexpr std::uint32_t kRange20Mask = 0x000FFFFFU;
constexpr std::uint32_t kRange19Mask = 0x0007FFFFU;
constexpr std::uint32_t kRange15Mask = 0x7FFFU;
constexpr std::uint32_t kRange15UnitMm = 8;  // RNG15: the SDK shifts the 15-bit range left by 3
constexpr std::uint16_t kNearIr8Scale = 16;  // RNG15_RFL8_NIR8: the SDK scales its 8-bit near-IR by 16

std::size_t pixel_bytes(UdpProfile profile) {
  return profile == UdpProfile::rng15_rfl8_nir8 ? 4 : 12;
}

}  // namespace

PacketLayout packet_layout(UdpProfile profile, int pixels_per_column, int columns_per_packet) {
  const bool legacy = profile == UdpProfile::legacy;
  PacketLayout l;
  l.packet_header_bytes = legacy ? 0 : kEudpPacketHeader;
  l.column_header_bytes = legacy ? kLegacyColumnHeader : kEudpColumnHeader;
  l.pixel_bytes = pixel_bytes(profile);
  l.column_footer_bytes = legacy ? kLegacyStatusBytes : 0;
  l.packet_footer_bytes = legacy ? 0 : kEudpPacketFooter;
  l.column_bytes = l.column_header_bytes + static_cast<std::size_t>(pixels_per_column) * l.pixel_bytes +
                   l.column_footer_bytes;
  l.packet_bytes = l.packet_header_bytes + static_cast<std::size_t>(columns_per_packet) * l.column_bytes +
                   l.packet_footer_bytes;
  return l;
}

PacketReader::PacketReader(UdpProfile profile, int pixels_per_column, int columns_per_packet)
    : profile_(profile), layout_(packet_layout(profile, pixels_per_column, columns_per_packet)) {}

std::size_t PacketReader::column_offset(int column) const {
  return layout_.packet_header_bytes + static_cast<std::size_t>(column) * layout_.column_bytes;
}

PacketHeader PacketReader::header(std::span<const std::uint8_t> packet) const {
  PacketHeader h;
  if (profile_ == UdpProfile::legacy) {
    return h;
  }
  h.packet_type = load_le<std::uint16_t>(packet, 0);
  h.frame_id = load_le<std::uint16_t>(packet, 2);
  h.initialization_id = load_le<std::uint32_t>(packet, 4) & 0x00FFFFFFU;
  for (std::size_t i = 0; i < 5; ++i) {  // 40-bit serial number at byte 7
    h.serial_number |= static_cast<std::uint64_t>(packet[7 + i]) << (8 * i);
  }
  return h;
}

ColumnHeader PacketReader::column(std::span<const std::uint8_t> packet, int column) const {
  const std::size_t at = column_offset(column);
  ColumnHeader c;
  c.timestamp_ns = load_le<std::uint64_t>(packet, at);
  c.measurement_id = load_le<std::uint16_t>(packet, at + kMeasurementIdOffset);
  if (profile_ == UdpProfile::legacy) {
    c.frame_id = load_le<std::uint16_t>(packet, at + kLegacyFrameIdOffset);
    c.status = load_le<std::uint32_t>(packet, at + layout_.column_bytes - kLegacyStatusBytes);
  } else {
    c.frame_id = load_le<std::uint16_t>(packet, 2);
    c.status = load_le<std::uint16_t>(packet, at + kEudpStatusOffset);
  }
  return c;
}

Pixel PacketReader::pixel(std::span<const std::uint8_t> packet, int column, int row) const {
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
