// SPDX-License-Identifier: Apache-2.0
// LZF decompression (Marc Lehmann's liblzf format), as PCD's binary_compressed data uses it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace rsu::io {

// `compressed` unpacked into exactly `expected_bytes` bytes; empty when the stream is malformed (a
// back reference before the start, a run past either end) or unpacks to another size.
std::optional<std::vector<std::uint8_t>> lzf_decompress(std::span<const std::uint8_t> compressed,
                                                        std::size_t expected_bytes);

}  // namespace rsu::io
