// SPDX-License-Identifier: Apache-2.0
// packet_layout and the column / pixel offsets (ouster_packet.h) against the sizes of Ouster's sensor
// docs ("Lidar Data Format", FW 2.x), worked out here from the field widths:
//   LEGACY: no packet header or footer; a column is a 16-byte header (timestamp u64, measurement id u16,
//     frame id u16, encoder count u32), 12 bytes per pixel, a 4-byte status: 16 columns of 64 pixels are
//     16 x (16 + 64 x 12 + 4) = 16 x 788 = 12608 bytes (the docs' 12608 for an OS-64).
//   eUDP profiles: a 32-byte packet header, a 12-byte column header (timestamp u64, measurement id u16,
//     status u16), the pixels, a 32-byte packet footer; 12-byte pixels in RNG19_RFL8_SIG16_NIR16, 4-byte
//     in RNG15_RFL8_NIR8 ("low data rate").
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lidar/ouster/ouster_packet.h"

namespace rsu::lidar::ouster {
namespace packet_layout_test {

struct ExpectedSize {
  UdpProfile profile;
  int pixels;
  std::size_t packet_bytes;
};

TEST(OusterPacketLayout, PacketSizesAreTheDocumentedOnes) {
  const ExpectedSize cases[] = {
      // LEGACY, 16 columns: 16 x (16 + N x 12 + 4).
      {UdpProfile::legacy, 16, 16 * (16 + 16 * 12 + 4)},  // 3392
      {UdpProfile::legacy, 32, 16 * (16 + 32 * 12 + 4)},  // 6464
      {UdpProfile::legacy, 64, 12608},                    // 16 x 788
      {UdpProfile::legacy, 128, 24896},                   // 16 x 1556
      // RNG19_RFL8_SIG16_NIR16: 32 + 16 x (12 + N x 12) + 32.
      {UdpProfile::rng19_rfl8_sig16_nir16, 16, 32 + 16 * (12 + 16 * 12) + 32},  // 3328
      {UdpProfile::rng19_rfl8_sig16_nir16, 64, 12544},                          // 64 + 16 x 780
      {UdpProfile::rng19_rfl8_sig16_nir16, 128, 24832},                         // 64 + 16 x 1548
      // RNG15_RFL8_NIR8: 32 + 16 x (12 + N x 4) + 32.
      {UdpProfile::rng15_rfl8_nir8, 64, 4352},   // 64 + 16 x 268
      {UdpProfile::rng15_rfl8_nir8, 128, 8448},  // 64 + 16 x 524
  };
  for (const ExpectedSize& c : cases) {
    const PacketLayout l = packet_layout(c.profile, c.pixels, 16);
    EXPECT_EQ(l.packet_bytes, c.packet_bytes) << to_string(c.profile) << " x " << c.pixels;
    EXPECT_LE(l.packet_bytes, kMaxUdpPayload);
  }
}

TEST(OusterPacketLayout, PartsOfEachProfile) {
  const PacketLayout legacy = packet_layout(UdpProfile::legacy, 64, 16);
  EXPECT_EQ(legacy.packet_header_bytes, 0U);
  EXPECT_EQ(legacy.column_header_bytes, 16U);
  EXPECT_EQ(legacy.pixel_bytes, 12U);
  EXPECT_EQ(legacy.column_footer_bytes, 4U);
  EXPECT_EQ(legacy.packet_footer_bytes, 0U);
  EXPECT_EQ(legacy.column_bytes, 788U);
  for (const UdpProfile p : {UdpProfile::rng19_rfl8_sig16_nir16, UdpProfile::rng15_rfl8_nir8}) {
    const PacketLayout l = packet_layout(p, 32, 16);
    EXPECT_EQ(l.packet_header_bytes, 32U);
    EXPECT_EQ(l.column_header_bytes, 12U);
    EXPECT_EQ(l.column_footer_bytes, 0U);
    EXPECT_EQ(l.packet_footer_bytes, 32U);
    const std::size_t pixel = p == UdpProfile::rng15_rfl8_nir8 ? 4 : 12;
    EXPECT_EQ(l.pixel_bytes, pixel);
    EXPECT_EQ(l.column_bytes, 12 + 32 * pixel);
  }
  // Fewer columns a packet (a sensor configured so): header + n columns + footer.
  EXPECT_EQ(packet_layout(UdpProfile::rng19_rfl8_sig16_nir16, 64, 8).packet_bytes, 32U + 8U * 780U + 32U);
  EXPECT_EQ(packet_layout(UdpProfile::legacy, 64, 0).packet_bytes, 0U);
}

// Little-endian writes of the test's own.
void put(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i)
    b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

// LEGACY, 16 pixels: a column is 16 + 16 x 12 + 4 = 212 bytes, so column 3 begins at 636: its
// measurement id at 644, frame id at 646, status at 636 + 208 = 844, row 5's pixel at 636 + 16 + 60 = 712.
TEST(OusterPacketLayout, LegacyColumnAndPixelOffsets) {
  const PacketReader reader(UdpProfile::legacy, 16, 16);
  std::vector<std::uint8_t> packet(reader.layout().packet_bytes, 0xAA);
  put(packet, 636, 0x1122334455667788ULL, 8);
  put(packet, 644, 1027, 2);
  put(packet, 646, 77, 2);
  put(packet, 844, 0xFFFFFFFFULL, 4);
  put(packet, 712, 0xFFF01234ULL, 4);  // range: the low 20 bits, 0x01234 = 4660 mm
  put(packet, 716, 300, 2);            // reflectivity
  put(packet, 718, 4000, 2);           // signal
  put(packet, 720, 900, 2);            // near-IR
  const ColumnHeader c = reader.column(packet, 3);
  EXPECT_EQ(c.timestamp_ns, 0x1122334455667788ULL);
  EXPECT_EQ(c.measurement_id, 1027);
  EXPECT_EQ(c.frame_id, 77);
  EXPECT_TRUE(c.valid());
  const Pixel p = reader.pixel(packet, 3, 5);
  EXPECT_EQ(p.range_mm, 0x01234U);
  EXPECT_EQ(p.reflectivity, 300);
  EXPECT_EQ(p.signal, 4000);
  EXPECT_EQ(p.near_ir, 900);
  EXPECT_EQ(reader.header(packet).packet_type, 0);  // LEGACY packets have no header
}

// RNG19_RFL8_SIG16_NIR16, 16 pixels: a column is 12 + 192 = 204 bytes after the 32-byte packet header,
// so column 3 begins at 32 + 612 = 644: measurement id at 652, status at 654, row 2's pixel at
// 644 + 12 + 24 = 680. The frame id is the packet header's (bytes 2-3).
TEST(OusterPacketLayout, EudpColumnAndPixelOffsets) {
  const PacketReader reader(UdpProfile::rng19_rfl8_sig16_nir16, 16, 16);
  std::vector<std::uint8_t> packet(reader.layout().packet_bytes, 0);
  put(packet, 0, 1, 2);                // packet type: lidar
  put(packet, 2, 0x1234, 2);           // frame id
  put(packet, 4, 0xABCDEF, 3);         // initialization id (24 bits)
  put(packet, 7, 0x0102030405ULL, 5);  // serial number (40 bits)
  put(packet, 644, 987654321ULL, 8);
  put(packet, 652, 2047, 2);
  put(packet, 654, 0x0001, 2);         // valid
  put(packet, 680, 0xFFF81234ULL, 4);  // range: the low 19 bits, 0x01234
  put(packet, 684, 200, 1);            // reflectivity u8
  put(packet, 685, 0x7F, 1);           // reserved
  put(packet, 686, 5000, 2);           // signal
  put(packet, 688, 700, 2);            // near-IR
  const PacketHeader h = reader.header(packet);
  EXPECT_EQ(h.packet_type, kLidarPacketType);
  EXPECT_EQ(h.frame_id, 0x1234);
  EXPECT_EQ(h.initialization_id, 0xABCDEFU);
  EXPECT_EQ(h.serial_number, 0x0102030405ULL);
  const ColumnHeader c = reader.column(packet, 3);
  EXPECT_EQ(c.timestamp_ns, 987654321ULL);
  EXPECT_EQ(c.measurement_id, 2047);
  EXPECT_EQ(c.frame_id, 0x1234);
  EXPECT_TRUE(c.valid());
  EXPECT_FALSE(reader.column(packet, 2).valid());
  const Pixel p = reader.pixel(packet, 3, 2);
  EXPECT_EQ(p.range_mm, 0x01234U);
  EXPECT_EQ(p.reflectivity, 200);
  EXPECT_EQ(p.signal, 5000);
  EXPECT_EQ(p.near_ir, 700);
}

// RNG15_RFL8_NIR8, 16 pixels: a column is 12 + 64 = 76 bytes, column 3 at 32 + 228 = 260, row 5's pixel
// at 260 + 12 + 20 = 292: range u16 (15 bits, 8 mm units), reflectivity u8, near-IR u8 (x 16).
TEST(OusterPacketLayout, LowDataRateColumnAndPixelOffsets) {
  const PacketReader reader(UdpProfile::rng15_rfl8_nir8, 16, 16);
  std::vector<std::uint8_t> packet(reader.layout().packet_bytes, 0);
  put(packet, 268, 1500, 2);    // column 3's measurement id
  put(packet, 292, 0x8123, 2);  // 0x0123 = 291 units of 8 mm = 2328 mm
  put(packet, 294, 45, 1);
  put(packet, 295, 10, 1);
  EXPECT_EQ(reader.column(packet, 3).measurement_id, 1500);
  const Pixel p = reader.pixel(packet, 3, 5);
  EXPECT_EQ(p.range_mm, 2328U);
  EXPECT_EQ(p.reflectivity, 45);
  EXPECT_EQ(p.signal, 0);
  EXPECT_EQ(p.near_ir, 160);
}

}  // namespace packet_layout_test
}  // namespace rsu::lidar::ouster
