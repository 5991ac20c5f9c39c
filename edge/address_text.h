// "HOST:PORT" text to a UDP endpoint and back. HOST is an IPv4 literal, an IPv6 literal in brackets
// ("[::1]:7000"), or a name the resolver knows ("localhost"). Used for the client's config and CLI.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/ip/udp.hpp>
#include <string>

namespace rsu::vehicle_client {

// Throws std::invalid_argument naming the problem. allow_port_zero: 0 means "any free port" (binding).
boost::asio::ip::udp::endpoint parse_udp_endpoint(const std::string& text, bool allow_port_zero = false);

std::string to_text(const boost::asio::ip::udp::endpoint& endpoint);

}  // namespace rsu::vehicle_client
