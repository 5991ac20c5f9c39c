// SPDX-License-Identifier: Apache-2.0
#include "daemon/udp_socket.h"

#include <linux/sock_diag.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "edge/arrival_stamp.h"

namespace rsu::daemon {

namespace asio = boost::asio;

void bind_udp(asio::ip::udp::socket& socket, const asio::ip::udp::endpoint& endpoint, const char* what) {
  boost::system::error_code ec;
  socket.open(endpoint.protocol(), ec);
  if (!ec)
    socket.bind(endpoint, ec);
  if (ec) {
    throw std::runtime_error(std::string("cannot bind the ") + what + " socket to " +
                             endpoint.address().to_string() + ":" + std::to_string(endpoint.port()) + ": " +
                             ec.message());
  }
}

std::size_t request_receive_buffer(asio::ip::udp::socket& socket, std::size_t bytes, const char* what) {
  boost::system::error_code ec;
  socket.set_option(asio::socket_base::receive_buffer_size(static_cast<int>(bytes)), ec);
  if (ec)
    spdlog::warn("{} socket: cannot ask for a {} byte receive buffer: {}", what, bytes, ec.message());
  asio::socket_base::receive_buffer_size granted;
  socket.get_option(granted, ec);
  if (ec) {
    spdlog::warn("{} socket: cannot read its receive buffer size back: {}", what, ec.message());
    return 0;
  }
  // Linux reports double the size granted (half of it is bookkeeping); Asio halves it back on Linux.
  const auto usable = static_cast<std::size_t>(granted.value());
  if (usable < bytes) {
    spdlog::warn(
        "{} socket: asked for a {} byte receive buffer, the kernel granted {} (net.core.rmem_max caps it; "
        "raise it, e.g. with deploy/sysctl.d/60-rsud.conf): bursts beyond it are dropped by the kernel and "
        "counted as kernel_drops",
        what, bytes, usable);
  }
  return usable;
}

std::optional<std::uint64_t> kernel_drops(int socket_fd) {
  std::array<std::uint32_t, SK_MEMINFO_VARS> meminfo{};
  socklen_t length = sizeof(meminfo);
  if (::getsockopt(socket_fd, SOL_SOCKET, SO_MEMINFO, meminfo.data(), &length) != 0 ||
      length < sizeof(std::uint32_t) * (SK_MEMINFO_DROPS + 1))
    return std::nullopt;
  return meminfo[SK_MEMINFO_DROPS];
}

void request_arrival_stamps(int socket_fd, const char* what) {
  if (!edge::request_arrival_stamps(socket_fd))
    spdlog::warn("{} socket: no arrival timestamps ({}): datagrams are timed when read", what,
                 std::strerror(errno));
}

}  // namespace rsu::daemon
