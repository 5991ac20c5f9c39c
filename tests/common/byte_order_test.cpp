// SPDX-License-Identifier: Apache-2.0
// load_le (byte_order.h): the integer of sizeof(T) bytes, least significant first, at any offset,
// against values written out by hand from the bytes.
#include "common/byte_order.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

namespace rsu {
namespace {

constexpr std::array<std::uint8_t, 10> kBytes = {0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF, 0xFF, 0x00};

TEST(ByteOrder, LoadsLeastSignificantByteFirst) {
  EXPECT_EQ(load_le<std::uint8_t>(kBytes, 0), 0x01U);
  EXPECT_EQ(load_le<std::uint16_t>(kBytes, 0), 0x2301U);
  EXPECT_EQ(load_le<std::uint32_t>(kBytes, 0), 0x67452301U);
  EXPECT_EQ(load_le<std::uint64_t>(kBytes, 0), 0xEFCDAB8967452301ULL);
}

TEST(ByteOrder, LoadsAtAnyOffsetAlignedOrNot) {
  EXPECT_EQ(load_le<std::uint16_t>(kBytes, 1), 0x4523U);
  EXPECT_EQ(load_le<std::uint32_t>(kBytes, 3), 0xCDAB8967U);
  EXPECT_EQ(load_le<std::uint64_t>(kBytes, 2), 0x00FFEFCDAB896745ULL);
  EXPECT_EQ(load_le<std::uint16_t>(kBytes, 8), 0x00FFU);  // the last two bytes
}

// Bytes with the top bit set must not sign-extend into the higher bytes.
TEST(ByteOrder, HighBytesDoNotSignExtend) {
  const std::array<std::uint8_t, 8> ff = {0xFF, 0x80, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80};
  EXPECT_EQ(load_le<std::uint16_t>(ff, 0), 0x80FFU);
  EXPECT_EQ(load_le<std::uint32_t>(ff, 0), 0x000080FFU);
  EXPECT_EQ(load_le<std::uint64_t>(ff, 0), 0x80000000000080FFULL);
  const std::array<std::uint8_t, 8> all = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(load_le<std::uint64_t>(all, 0), 0xFFFFFFFFFFFFFFFFULL);
  EXPECT_EQ(load_le<std::uint32_t>(all, 4), 0xFFFFFFFFU);
}

// store_le writes what load_le reads, byte for byte as written out here.
TEST(ByteOrder, StoreWritesTheBytesLoadReads) {
  std::array<std::uint8_t, 12> buffer{};
  store_le<std::uint32_t>(buffer, 1, 0xDEADBEEFU);
  const std::array<std::uint8_t, 12> expected = {0x00, 0xEF, 0xBE, 0xAD, 0xDE, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(buffer, expected);
  EXPECT_EQ(load_le<std::uint32_t>(buffer, 1), 0xDEADBEEFU);
}

}  // namespace
}  // namespace rsu
