// SPDX-License-Identifier: Apache-2.0
// rsud's V2I receiver thread (v2i.verifier_thread: true; off by default, README "Robustness"): reads the
// announcement socket and checks each datagram's Ed25519 signature (v2i::check_signature_ahead, ~40 us each)
// off the event loop's thread, so that 1000 signed vehicles at 10 Hz neither wait behind a LiDAR rotation's
// work nor hold it up. The datagrams, each with its check, go to the event loop in arrival order, where
// RsuCore does everything else (rate limit, rights, time and replay windows, registry): its state is touched
// by that thread only. The socket stays the event loop's for sending (corrections, notices).
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "v2i/message_authenticator.h"
#include "v2i/security/trust_list.h"

namespace rsu::daemon {

struct ReceivedDatagram {
  std::vector<std::uint8_t> bytes;
  boost::asio::ip::udp::endpoint sender;
  std::optional<v2i::SignatureCheck> signature;  // none: nothing to check ahead (insecure mode, unsigned...)
  std::optional<TimeNs> received;                // the kernel's stamp of its arrival (SO_TIMESTAMPNS), if any
};

class V2iReceiver {
 public:
  // Starts the thread on `socket_fd` (not owned: it stays open until stop() returned). `on_arrival` is
  // posted to `io` whenever datagrams wait and none was posted since the last take(). Signatures are
  // checked against `trust` when `verify` (signed mode). At most `max_waiting` datagrams wait; beyond
  // that they are dropped and counted (dropped_full()), so that a stalled loop cannot exhaust memory.
  // `window`: the time window (security.max_age_s, max_future_s) on the host's clock; a datagram generated
  // outside it is not checked ahead (the event loop refuses it before its signature). None: check all
  // (rsud replaying a capture runs on the capture's clock).
  // `verify_within`: an announcement beyond it is not checked ahead either (with a window only; the event
  // loop drops it unverified, v2i::VerificationRadius).
  V2iReceiver(int socket_fd, boost::asio::io_context& io, std::function<void()> on_arrival, bool verify,
              v2i::security::TrustList trust, std::size_t max_waiting,
              std::optional<v2i::security::ReplayConfig> window,
              std::optional<v2i::VerificationRadius> verify_within);
  ~V2iReceiver();
  V2iReceiver(const V2iReceiver&) = delete;
  V2iReceiver& operator=(const V2iReceiver&) = delete;

  // Ends the thread and waits for it (prompt: it is woken). Idempotent.
  void stop();
  // SIGHUP: later datagrams are checked against this list (RsuCore verifies again any checked against a
  // key the reloaded list no longer holds).
  void set_trust(bool verify, v2i::security::TrustList trust,
                 std::optional<v2i::security::ReplayConfig> window,
                 std::optional<v2i::VerificationRadius> verify_within);
  // Up to `at_most` of the waiting datagrams, oldest first (event loop thread). When some are left,
  // the caller is expected to come back (no new on_arrival is posted until a take() empties the queue).
  std::vector<ReceivedDatagram> take(std::size_t at_most);

  std::uint64_t dropped_full() const { return dropped_full_.load(std::memory_order_relaxed); }
  std::uint64_t receive_errors() const { return receive_errors_.load(std::memory_order_relaxed); }
  std::size_t waiting_max() const { return waiting_max_.load(std::memory_order_relaxed); }

 private:
  void run();
  void hand_over(std::vector<ReceivedDatagram>& batch);

  int socket_fd_;
  int wake_fd_ = -1;  // an eventfd: stop() writes it, the thread polls it with the socket
  boost::asio::io_context& io_;
  std::function<void()> on_arrival_;
  std::size_t max_waiting_;

  std::mutex trust_mutex_;
  bool verify_;
  std::shared_ptr<const v2i::security::TrustList> trust_;
  std::optional<v2i::security::ReplayConfig> window_;
  std::optional<v2i::VerificationRadius> verify_within_;

  std::mutex queue_mutex_;
  std::deque<ReceivedDatagram> waiting_;
  bool arrival_posted_ = false;

  std::atomic<std::uint64_t> dropped_full_{0};
  std::atomic<std::uint64_t> receive_errors_{0};
  std::atomic<std::size_t> waiting_max_{0};
  std::thread thread_;
};

}  // namespace rsu::daemon
