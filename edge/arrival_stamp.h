// SPDX-License-Identifier: Apache-2.0
// A datagram's arrival on the host's clock (CLOCK_REALTIME, as host_now_ns), stamped by the kernel as it
// reached the socket, however long it then waited there for the program to read it: what rsud judges
// an announcement's time windows from, and what the load test's vehicles time a correction's arrival by
// (issue 16: latency to the correction on the wire, not to a busy load generator's reading it).
// Either in each message's control data (request_arrival_stamps: SO_TIMESTAMPNS, read by recvmsg /
// recvmmsg with arrival_in), or, on a socket without SO_TIMESTAMPNS, for the datagram read last
// (last_arrival: SIOCGSTAMPNS; its first call turns the stamps on and finds none). Linux switches its
// stamping on for the host a moment after the first socket asks (net_enable_timestamp, deferred): a
// datagram that arrives before then is stamped when it is read.
#pragma once

#include <sys/socket.h>
#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <span>

#include "common/time.h"

namespace rsu::edge {

// False where the kernel refuses (errno says why).
bool request_arrival_stamps(int socket_fd);
std::optional<TimeNs> arrival_in(const msghdr& message);
std::optional<TimeNs> last_arrival(int socket_fd);

// One datagram read into `buffer` by recvmsg (flags as recvmsg's), with its stamp where the socket was
// asked for them: bytes is recvmsg's result (-1 and errno on failure).
struct StampedRead {
  ssize_t bytes = -1;
  std::optional<TimeNs> arrival;
};
StampedRead read_stamped(int socket_fd, std::span<std::uint8_t> buffer, int flags = 0);

}  // namespace rsu::edge
