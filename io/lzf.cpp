// SPDX-License-Identifier: Apache-2.0
#include "io/lzf.h"

namespace rsu::io {

// The format: a control byte c. c < 32: a literal run of c + 1 bytes follows. Otherwise a back
// reference: length (c >> 5) + 2, where a length field of 7 continues in the next byte (+ that byte);
// distance ((c & 31) << 8) + the next byte + 1, counted back from the end of the output so far. The
// copy may overlap its own output (a run), so it goes byte by byte.
std::optional<std::vector<std::uint8_t>> lzf_decompress(std::span<const std::uint8_t> in,
                                                        std::size_t expected_bytes) {
  std::vector<std::uint8_t> out;
  out.reserve(expected_bytes);
  std::size_t i = 0;
  while (i < in.size()) {
    const std::size_t c = in[i++];
    if (c < 32) {
      const std::size_t n = c + 1;
      if (n > in.size() - i || n > expected_bytes - out.size())
        return std::nullopt;
      out.insert(out.end(), in.begin() + static_cast<std::ptrdiff_t>(i),
                 in.begin() + static_cast<std::ptrdiff_t>(i + n));
      i += n;
      continue;
    }
    std::size_t n = c >> 5;
    if (n == 7) {
      if (i >= in.size())
        return std::nullopt;
      n += in[i++];
    }
    n += 2;
    if (i >= in.size())
      return std::nullopt;
    const std::size_t distance = ((c & 31U) << 8) + in[i++] + 1;
    if (distance > out.size() || n > expected_bytes - out.size())
      return std::nullopt;
    const std::size_t from = out.size() - distance;
    for (std::size_t k = 0; k < n; ++k)
      out.push_back(out[from + k]);
  }
  if (out.size() != expected_bytes)
    return std::nullopt;
  return out;
}

}  // namespace rsu::io
