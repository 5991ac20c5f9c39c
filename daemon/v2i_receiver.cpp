// SPDX-License-Identifier: Apache-2.0
#include "daemon/v2i_receiver.h"

#include <poll.h>
#include <pthread.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>
#include <boost/asio/post.hpp>

#include "daemon/udp_socket.h"
#include "edge/arrival_stamp.h"
#include "edge/host_clock.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rsu::daemon {

namespace {

// Datagrams read per recvmmsg call; each buffer holds any UDP datagram, so none is truncated.
constexpr std::size_t kBatch = 16;
constexpr std::size_t kDatagramBytes = 65536;

}  // namespace

V2iReceiver::V2iReceiver(int socket_fd, boost::asio::io_context& io, std::function<void()> on_arrival,
                         bool verify, v2i::security::TrustList trust, std::size_t max_waiting,
                         std::optional<v2i::security::ReplayConfig> window,
                         std::optional<v2i::VerificationRadius> verify_within)
    : socket_fd_(socket_fd),
      io_(io),
      on_arrival_(std::move(on_arrival)),
      max_waiting_(max_waiting),
      verify_(verify),
      trust_(std::make_shared<const v2i::security::TrustList>(std::move(trust))),
      window_(window),
      verify_within_(verify_within) {
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC);
  if (wake_fd_ < 0)
    throw std::runtime_error(std::string("V2I receiver thread: eventfd: ") + std::strerror(errno));
  thread_ = std::thread([this] { run(); });
}

V2iReceiver::~V2iReceiver() {
  stop();
  if (wake_fd_ >= 0)
    ::close(wake_fd_);
}

void V2iReceiver::stop() {
  if (!thread_.joinable())
    return;
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t written = ::write(wake_fd_, &one, sizeof(one));
  thread_.join();
}

void V2iReceiver::set_trust(bool verify, v2i::security::TrustList trust,
                            std::optional<v2i::security::ReplayConfig> window,
                            std::optional<v2i::VerificationRadius> verify_within) {
  auto next = std::make_shared<const v2i::security::TrustList>(std::move(trust));
  const std::lock_guard lock(trust_mutex_);
  verify_ = verify;
  trust_ = std::move(next);
  window_ = window;
  verify_within_ = verify_within;
}

std::vector<ReceivedDatagram> V2iReceiver::take(std::size_t at_most) {
  std::vector<ReceivedDatagram> out;
  const std::lock_guard lock(queue_mutex_);
  const std::size_t n = std::min(at_most, waiting_.size());
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(std::move(waiting_.front()));
    waiting_.pop_front();
  }
  if (waiting_.empty())
    arrival_posted_ = false;
  return out;
}

void V2iReceiver::hand_over(std::vector<ReceivedDatagram>& batch) {
  bool post = false;
  {
    const std::lock_guard lock(queue_mutex_);
    for (ReceivedDatagram& d : batch) {
      if (waiting_.size() >= max_waiting_) {
        dropped_full_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      waiting_.push_back(std::move(d));
    }
    if (waiting_.size() > waiting_max_.load(std::memory_order_relaxed))
      waiting_max_.store(waiting_.size(), std::memory_order_relaxed);
    if (!waiting_.empty() && !arrival_posted_) {
      arrival_posted_ = true;
      post = true;
    }
  }
  batch.clear();
  if (post)
    boost::asio::post(io_, on_arrival_);
}

void V2iReceiver::run() {
  // Named so that top -H and the load test (tests/load/rsud_load.py) can tell its CPU from the loop's.
  ::pthread_setname_np(::pthread_self(), "rsud-v2i");
  std::vector<std::array<std::uint8_t, kDatagramBytes>> buffers(kBatch);
  std::array<sockaddr_storage, kBatch> senders{};
  std::array<iovec, kBatch> iov{};
  std::array<mmsghdr, kBatch> headers{};
  // Room for each datagram's arrival stamp (SO_TIMESTAMPNS, asked for on the socket by rsud).
  std::array<std::array<char, CMSG_SPACE(sizeof(timespec))>, kBatch> controls{};
  std::vector<ReceivedDatagram> batch;
  batch.reserve(kBatch);
  std::array<pollfd, 2> fds{pollfd{socket_fd_, POLLIN, 0}, pollfd{wake_fd_, POLLIN, 0}};
  for (;;) {
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR)
        continue;
      receive_errors_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (fds[1].revents != 0)
      return;  // stop()
    // Drain what the kernel holds, a batch per call, before polling again.
    for (;;) {
      for (std::size_t i = 0; i < kBatch; ++i) {
        iov[i] = iovec{buffers[i].data(), buffers[i].size()};
        headers[i] = mmsghdr{};
        headers[i].msg_hdr.msg_name = &senders[i];
        headers[i].msg_hdr.msg_namelen = sizeof(sockaddr_storage);
        headers[i].msg_hdr.msg_iov = &iov[i];
        headers[i].msg_hdr.msg_iovlen = 1;
        headers[i].msg_hdr.msg_control = controls[i].data();
        headers[i].msg_hdr.msg_controllen = controls[i].size();
      }
      const int n = ::recvmmsg(socket_fd_, headers.data(), kBatch, MSG_DONTWAIT, nullptr);
      if (n <= 0) {
        // EAGAIN: drained. Anything else (an ICMP error for an earlier correction, say) is not fatal.
        if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
          receive_errors_.fetch_add(1, std::memory_order_relaxed);
        break;
      }
      std::shared_ptr<const v2i::security::TrustList> trust;
      bool verify = false;
      std::optional<v2i::security::ReplayConfig> window;
      std::optional<v2i::VerificationRadius> verify_within;
      {
        const std::lock_guard lock(trust_mutex_);
        trust = trust_;
        verify = verify_;
        window = window_;
        verify_within = verify_within_;
      }
      const TimeNs now = edge::host_now_ns();
      for (int i = 0; i < n; ++i) {
        ReceivedDatagram d;
        const auto* data = buffers[static_cast<std::size_t>(i)].data();
        d.bytes.assign(data, data + headers[static_cast<std::size_t>(i)].msg_len);
        const socklen_t length = headers[static_cast<std::size_t>(i)].msg_hdr.msg_namelen;
        if (length > d.sender.capacity())
          continue;  // not an IP sender: cannot happen on a UDP socket
        std::memcpy(d.sender.data(), &senders[static_cast<std::size_t>(i)], length);
        d.sender.resize(length);
        d.received = edge::arrival_in(headers[static_cast<std::size_t>(i)].msg_hdr);
        if (verify && window)
          d.signature = v2i::check_signature_ahead(d.bytes, *trust,
                                                   {now, window->max_age, window->max_future}, verify_within);
        else if (verify)
          d.signature = v2i::check_signature_ahead(d.bytes, *trust);
        batch.push_back(std::move(d));
      }
      hand_over(batch);
      if (static_cast<std::size_t>(n) < kBatch)
        break;
    }
  }
}

}  // namespace rsu::daemon
