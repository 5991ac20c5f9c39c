// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's UDP sockets: binding with a clear error, the receive buffer asked of the kernel and read
// back, and the kernel's own count of datagrams it dropped for a socket (its buffer was full), so that
// what was sent and what rsud received can be told apart in its statistics.
#include <sys/socket.h>
#include <boost/asio/ip/udp.hpp>

#include <cstdint>
#include <optional>

namespace rsu::daemon {

// Opens and binds `socket`, or throws naming `what` and the endpoint.
void bind_udp(boost::asio::ip::udp::socket& socket, const boost::asio::ip::udp::endpoint& endpoint,
              const char* what);

// Asks for a receive buffer of `bytes` and returns what the kernel granted. Linux caps the request at
// net.core.rmem_max without an error; a grant below the request is
// logged as a warning naming the sysctl that caps it (deploy/ ships a sysctl.d snippet).
std::size_t request_receive_buffer(boost::asio::ip::udp::socket& socket, std::size_t bytes, const char* what);

// Datagrams the kernel dropped for this socket since it was opened (SO_MEMINFO's drop count), or nothing
// where the kernel cannot say (before Linux 4.12).
std::optional<std::uint64_t> kernel_drops(int socket_fd);

// Asks the kernel to stamp each datagram's arrival (edge/arrival_stamp.h, which reads the stamps); logs a
// warning naming `what` where it refuses.
void request_arrival_stamps(int socket_fd, const char* what);

}  // namespace rsu::daemon
