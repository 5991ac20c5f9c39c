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

}  // namespace rsu::lidar::ouster
