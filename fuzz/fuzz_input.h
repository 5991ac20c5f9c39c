// SPDX-License-Identifier: Apache-2.0
// A cursor over a fuzzer's input for the harnesses that split it into several messages: fixed-width
// little-endian integers and length-prefixed records, the same framing make_seed_corpus.cpp writes.
// Reading past the end yields zeros and short records, never out of bounds.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

namespace rsu::fuzz {

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : bytes_(data, size) {}

  bool empty() const { return pos_ >= bytes_.size(); }

  std::uint8_t u8() { return empty() ? 0 : bytes_[pos_++]; }
  std::uint16_t u16() {
    const std::uint16_t lo = u8();
    return static_cast<std::uint16_t>(lo | (u8() << 8));
  }
  // The next `n` bytes, or fewer at the end of the input.
  std::span<const std::uint8_t> take(std::size_t n) {
    const std::size_t k = std::min(n, bytes_.size() - std::min(pos_, bytes_.size()));
    const std::span<const std::uint8_t> out = bytes_.subspan(std::min(pos_, bytes_.size()), k);
    pos_ += k;
    return out;
  }
  // A record: a u16 length, then that many bytes (or what is left).
  std::span<const std::uint8_t> record() { return take(u16()); }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

}  // namespace rsu::fuzz
