// SPDX-License-Identifier: Apache-2.0
// Little-endian integers in byte buffers: sensor packets are little-endian whatever the host is.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>

namespace rsu {

// The unsigned integer of sizeof(T) bytes at `at`, least significant byte first. The caller has
// checked that the bytes exist.
template <std::unsigned_integral T>
T load_le(std::span<const std::uint8_t> bytes, std::size_t at) {
  T value = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    value = static_cast<T>(value | (static_cast<T>(bytes[at + i]) << (8 * i)));
  }
  return value;
}

// Writes `value` as sizeof(T) bytes at `at`, least significant byte first.
template <std::unsigned_integral T>
void store_le(std::span<std::uint8_t> bytes, std::size_t at, T value) {
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    bytes[at + i] = static_cast<std::uint8_t>((value >> (8 * i)) & 0xFFU);
  }
}

}  // namespace rsu
