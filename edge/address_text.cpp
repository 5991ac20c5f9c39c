// SPDX-License-Identifier: Apache-2.0
#include "edge/address_text.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <charconv>
#include <stdexcept>

namespace rsu::edge {

namespace asio = boost::asio;

namespace {

unsigned short parse_port(const std::string& text, const std::string& whole, bool allow_zero) {
  unsigned value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end || value > 65535 || (value == 0 && !allow_zero)) {
    throw std::invalid_argument("\"" + whole + "\": port must be " + (allow_zero ? "0" : "1") +
                                "..65535, got \"" + text + "\"");
  }
  return static_cast<unsigned short>(value);
}

}  // namespace

asio::ip::address parse_ip_address(const std::string& text, const std::string& what) {
  boost::system::error_code ec;
  const asio::ip::address address = asio::ip::make_address(text, ec);
  if (ec)
    throw std::invalid_argument(what + ": \"" + text + "\" is not an IP address");
  return address;
}

asio::ip::udp::endpoint parse_udp_endpoint(const std::string& text, bool allow_port_zero) {
  std::string host;
  std::string port;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      throw std::invalid_argument("\"" + text + "\": expected [IPV6]:PORT");
    }
    host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || text.find(':') != colon) {
      throw std::invalid_argument("\"" + text + "\": expected HOST:PORT (IPv6 as [ADDR]:PORT)");
    }
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  if (host.empty()) {
    throw std::invalid_argument("\"" + text + "\": empty host");
  }
  const unsigned short port_number = parse_port(port, text, allow_port_zero);
  boost::system::error_code ec;
  const asio::ip::address address = asio::ip::make_address(host, ec);
  if (!ec) {
    return {address, port_number};
  }
  // Not a literal: ask the resolver (done once at start-up, never per message).
  asio::io_context io;
  asio::ip::udp::resolver resolver(io);
  const auto results = resolver.resolve(host, port, ec);
  if (ec || results.empty()) {
    throw std::invalid_argument("\"" + text + "\": cannot resolve host \"" + host + "\"");
  }
  return results.begin()->endpoint();
}

std::string to_text(const asio::ip::udp::endpoint& endpoint) {
  const std::string address = endpoint.address().to_string();
  return (endpoint.address().is_v6() ? "[" + address + "]" : address) + ":" + std::to_string(endpoint.port());
}

}  // namespace rsu::edge
