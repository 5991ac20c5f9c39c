// SPDX-License-Identifier: Apache-2.0
// Addresses as text, for every program at the edge: an IP address ("192.0.2.7", "::1"), and a
// "HOST:PORT" UDP endpoint and back, where HOST is an IPv4 literal, an IPv6 literal in brackets
// ("[::1]:7000") or a name the resolver knows ("localhost"). (What a received announcement carries is
// checked by lib/v2i's pure parser, v2i/ip_literal.h.)
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>
#include <string>

namespace rsu::edge {

// An IP address literal (no names). Throws std::invalid_argument: "<what>: "<text>" is not an IP address".
boost::asio::ip::address parse_ip_address(const std::string& text, const std::string& what);

// Throws std::invalid_argument naming the problem. allow_port_zero: 0 means "any free port" (binding).
boost::asio::ip::udp::endpoint parse_udp_endpoint(const std::string& text, bool allow_port_zero = false);

std::string to_text(const boost::asio::ip::udp::endpoint& endpoint);

}  // namespace rsu::edge
