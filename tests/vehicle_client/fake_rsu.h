// SPDX-License-Identifier: Apache-2.0
// A fake RSU for the client tests: one plain POSIX UDP socket on 127.0.0.1 with a receive timeout, so
// every wait in a test is bounded.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsu::vehicle_client::test {

class FakeRsu {
 public:
  FakeRsu() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd_ < 0) {
      throw std::runtime_error("socket() failed");
    }
    timeval timeout{0, 50'000};  // 50 ms per receive attempt
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
    sockaddr_in address = loopback(0);
    if (::bind(fd_, as_sockaddr(&address), sizeof(address)) != 0) {
      throw std::runtime_error("bind() failed");
    }
    socklen_t length = sizeof(address);
    ::getsockname(fd_, as_sockaddr(&address), &length);
    port_ = ntohs(address.sin_port);
  }
  ~FakeRsu() { ::close(fd_); }
  FakeRsu(const FakeRsu&) = delete;
  FakeRsu& operator=(const FakeRsu&) = delete;

  std::uint16_t port() const { return port_; }
  std::string endpoint_text() const { return "127.0.0.1:" + std::to_string(port_); }

  // One datagram, or nothing after `attempts` receive timeouts of 50 ms.
  std::optional<std::vector<std::uint8_t>> receive(int attempts = 40) {
    std::vector<std::uint8_t> buffer(4096);
    for (int i = 0; i < attempts; ++i) {
      const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), 0);
      if (n >= 0) {
        buffer.resize(static_cast<std::size_t>(n));
        return buffer;
      }
    }
    return std::nullopt;
  }

  void send_to(const std::vector<std::uint8_t>& bytes, const std::string& address, std::uint32_t port) {
    sockaddr_in to = loopback(static_cast<std::uint16_t>(port));
    if (::inet_pton(AF_INET, address.c_str(), &to.sin_addr) != 1) {
      throw std::runtime_error("bad address " + address);
    }
    const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0, as_sockaddr(&to), sizeof(to));
    if (n != static_cast<ssize_t>(bytes.size())) {
      throw std::runtime_error("sendto() failed");
    }
  }

 private:
  static sockaddr_in loopback(std::uint16_t port) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return a;
  }
  static sockaddr* as_sockaddr(sockaddr_in* a) { return reinterpret_cast<sockaddr*>(a); }

  int fd_ = -1;
  std::uint16_t port_ = 0;
};

}  // namespace rsu::vehicle_client::test
