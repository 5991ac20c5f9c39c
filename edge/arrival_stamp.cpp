// SPDX-License-Identifier: Apache-2.0
#include "edge/arrival_stamp.h"

#include <linux/sockios.h>
#include <sys/ioctl.h>
#include <time.h>

#include <array>
#include <cstring>

namespace rsu::edge {
namespace {

TimeNs to_ns(const timespec& t) {
  return static_cast<TimeNs>(t.tv_sec) * kNsPerSecond + t.tv_nsec;
}

}  // namespace

bool request_arrival_stamps(int socket_fd) {
  const int on = 1;
  return ::setsockopt(socket_fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) == 0;
}

std::optional<TimeNs> last_arrival(int socket_fd) {
  timespec t{};
  if (::ioctl(socket_fd, SIOCGSTAMPNS, &t) != 0)
    return std::nullopt;
  return to_ns(t);
}

std::optional<TimeNs> arrival_in(const msghdr& message) {
  // CMSG_NXTHDR takes a non-const msghdr; it only reads it.
  auto& m = const_cast<msghdr&>(message);
  for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS &&
        c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
      timespec t{};
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      return to_ns(t);
    }
  }
  return std::nullopt;
}

StampedRead read_stamped(int socket_fd, std::span<std::uint8_t> buffer, int flags) {
  alignas(cmsghdr) std::array<char, CMSG_SPACE(sizeof(timespec))> control{};
  iovec io{buffer.data(), buffer.size()};
  msghdr message{};
  message.msg_iov = &io;
  message.msg_iovlen = 1;
  message.msg_control = control.data();
  message.msg_controllen = control.size();
  StampedRead out;
  out.bytes = ::recvmsg(socket_fd, &message, flags);
  if (out.bytes >= 0)
    out.arrival = arrival_in(message);
  return out;
}

}  // namespace rsu::edge
