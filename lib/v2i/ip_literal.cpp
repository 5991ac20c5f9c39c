// SPDX-License-Identifier: Apache-2.0
#include "v2i/ip_literal.h"

#include <arpa/inet.h>  // inet_pton only: a pure string-to-bytes parser, no socket is involved

#include <algorithm>
#include <cstring>
#include <string>

namespace rsu::v2i {

std::optional<IpLiteral> parse_ip_literal(std::string_view text) {
  // An embedded NUL would let "192.0.2.1\0junk" pass as its prefix.
  if (text.empty() || text.size() > 64 || text.find('\0') != std::string_view::npos)
    return std::nullopt;
  const std::string terminated(text);
  IpLiteral out;
  std::array<unsigned char, 4> v4{};
  if (inet_pton(AF_INET, terminated.c_str(), v4.data()) == 1) {
    out.bytes[10] = 0xff;
    out.bytes[11] = 0xff;
    std::memcpy(out.bytes.data() + 12, v4.data(), 4);
    out.ipv4 = true;
    return out;
  }
  if (inet_pton(AF_INET6, terminated.c_str(), out.bytes.data()) == 1)
    return out;
  return std::nullopt;
}

bool is_unicast(const IpLiteral& address) {
  const auto& b = address.bytes;
  // An IPv4-mapped IPv6 literal (::ffff:a.b.c.d, RFC 4291 2.5.5.2) is the IPv4 address to a dual-stack
  // socket, whichever way it was written: "::ffff:224.0.0.1" is a multicast group as "224.0.0.1" is.
  const bool mapped = std::all_of(b.begin(), b.begin() + 10, [](unsigned char x) { return x == 0; }) &&
                      b[10] == 0xff && b[11] == 0xff;
  if (mapped) {
    const bool unspecified = b[12] == 0;  // 0.0.0.0/8: "this network"
    const bool multicast = b[12] >= 224 && b[12] <= 239;
    const bool broadcast = b[12] == 255 && b[13] == 255 && b[14] == 255 && b[15] == 255;
    return !unspecified && !multicast && !broadcast;
  }
  const bool all_zero = std::all_of(b.begin(), b.end(), [](unsigned char x) { return x == 0; });
  const bool multicast = b[0] == 0xff;
  return !all_zero && !multicast;
}

bool same_host(std::string_view a, std::string_view b) {
  const std::optional<IpLiteral> x = parse_ip_literal(a);
  const std::optional<IpLiteral> y = parse_ip_literal(b);
  return x && y && x->bytes == y->bytes;
}

}  // namespace rsu::v2i
