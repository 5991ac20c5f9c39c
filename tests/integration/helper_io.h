// SPDX-License-Identifier: Apache-2.0
// Shared by the integration test helpers (announcer.cpp, send_datagram.cpp): an IPv4 socket address
// from text and a small file's text, each empty when impossible (the caller says why and exits).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cstdint>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace rsu::integration {

inline std::optional<sockaddr_in> ipv4_endpoint(const std::string& ip, int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, ip.c_str(), &a.sin_addr) != 1)
    return std::nullopt;
  return a;
}

inline std::optional<std::string> file_text(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace rsu::integration
