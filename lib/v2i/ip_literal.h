// SPDX-License-Identifier: Apache-2.0
// Numeric IP address literals ("192.0.2.7", "2001:db8::1"), as announcements carry their reply_to and
// as the daemon names a datagram's sender: the one parser every check of an address uses. Pure (the
// C library's inet_pton turns text into bytes; no socket is involved).
#pragma once

#include <array>
#include <optional>
#include <string_view>

namespace rsu::v2i {

struct IpLiteral {
  // IPv6 byte order; an IPv4 literal as IPv4-mapped IPv6 (::ffff:a.b.c.d), so that the two spellings
  // of one host compare equal.
  std::array<unsigned char, 16> bytes{};
  bool ipv4 = false;  // written as an IPv4 literal
};

// Empty unless `text` is a whole IPv4 or IPv6 literal (no host names, ports, brackets or zone ids; at
// most 64 characters, no embedded NUL).
std::optional<IpLiteral> parse_ip_literal(std::string_view text);

// A literal that names one host: not unspecified (0.0.0.0/8, ::), multicast or IPv4 broadcast (an
// IPv4-mapped IPv6 literal judged as its IPv4 address).
bool is_unicast(const IpLiteral& address);

// Whether both are literals of the same host, whatever the spelling ("127.0.0.1" and the dual-stack
// "::ffff:127.0.0.1" are one).
bool same_host(std::string_view a, std::string_view b);

}  // namespace rsu::v2i
