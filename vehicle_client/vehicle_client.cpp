// SPDX-License-Identifier: Apache-2.0
#include "vehicle_client/vehicle_client.h"

#include <array>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <chrono>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "edge/address_text.h"

namespace rsu::vehicle_client {

namespace asio = boost::asio;
using udp = asio::ip::udp;

namespace {

// Room for the largest valid datagram and then some: anything longer arrives truncated to this size,
// which is still over v2i::kMaxDatagramBytes, so the decoder refuses it as too large.
constexpr std::size_t kReceiveBufferBytes = 2048;

struct Outgoing {
  udp::endpoint destination;
  std::vector<std::uint8_t> bytes;
};

}  // namespace

class VehicleClient::Impl : public std::enable_shared_from_this<Impl> {
 public:
  Impl(asio::io_context& io, const VehicleClientConfig& config, Clock clock)
      : strand_(asio::make_strand(io)),
        socket_(strand_),
        keepalive_(strand_),
        config_(config),
        clock_(std::move(clock)),
        filter_({config.vehicle_id, config.max_tracked_rsus, config.security, config.trust_list}),
        announcer_({config.vehicle_id, config.size, config.reference_offset, config.announce_period,
                    config.max_resend_age},
                   config.security.mode == v2i::SecurityMode::kSigned ? config.signing_key : std::nullopt) {
    if (config_.vehicle_id == 0) {
      throw std::invalid_argument("vehicle id must be non-zero");
    }
    if (config_.rsu_endpoints.empty()) {
      throw std::invalid_argument("at least one RSU endpoint is needed");
    }
    if (!clock_) {
      throw std::invalid_argument("no clock given");
    }
    for (const std::string& text : config_.rsu_endpoints) {
      rsus_.push_back(edge::parse_udp_endpoint(text));
      if (rsus_.back().protocol() != rsus_.front().protocol()) {
        throw std::invalid_argument("RSU endpoints mix IPv4 and IPv6: " + config_.rsu_endpoints.front() +
                                    ", " + text);
      }
    }
    if (config_.security.mode == v2i::SecurityMode::kSigned && !config_.signing_key) {
      throw std::invalid_argument("signed mode needs the vehicle's signing key");
    }
    udp::endpoint bind_to(rsus_.front().protocol(), config_.bind_port);
    if (!config_.bind_address.empty()) {
      boost::system::error_code ec;
      bind_to.address(asio::ip::make_address(config_.bind_address, ec));
      if (ec) {
        throw std::invalid_argument("bind address \"" + config_.bind_address + "\" is not an IP address");
      }
      if (bind_to.protocol() != rsus_.front().protocol()) {
        throw std::invalid_argument("bind address and RSU endpoints are of different address families");
      }
    }
    socket_.open(bind_to.protocol());
    socket_.bind(bind_to);
    // Sends are synchronous on the io thread: non-blocking, so a full send buffer drops (and counts) a
    // datagram instead of stalling the receive side.
    socket_.non_blocking(true);
    local_ = socket_.local_endpoint();
    for (const udp::endpoint& rsu : rsus_) {
      reply_to_.push_back({reply_address_for(rsu), local_.port()});
    }
  }

  void start() {
    asio::post(strand_, [self = shared_from_this()] {
      self->receive_next();
      self->arm_keepalive();
    });
  }

  void stop() {
    {
      const std::lock_guard lock(mutex_);
      if (stopped_) {
        return;
      }
      stopped_ = true;
    }
    {
      // Waits for a callback running on the io thread; recursive so that a callback may call stop().
      const std::lock_guard callback_lock(callback_mutex_);
      callback_ = nullptr;
    }
    asio::post(strand_, [self = shared_from_this()] {
      boost::system::error_code ignored;
      self->keepalive_.cancel();
      self->socket_.close(ignored);
    });
  }

  v2i::AnnouncementReason announce(const VehicleState& state) {
    std::vector<Outgoing> outgoing;
    {
      const std::lock_guard lock(mutex_);
      if (stopped_) {
        return v2i::AnnouncementReason::kValid;
      }
      const v2i::AnnouncementReason reason = build(state, outgoing);
      if (reason != v2i::AnnouncementReason::kValid) {
        ++stats_.announcements_refused;
        return reason;
      }
      // Queued while the sequence numbers are still ours alone: a keep-alive built after this
      // announcement must not reach the strand, and the RSU, before it (the RSU would refuse this one
      // as stale).
      send(std::move(outgoing), false);
    }
    return v2i::AnnouncementReason::kValid;
  }

  std::vector<ReceivedCorrection> poll() {
    const std::lock_guard lock(mutex_);
    std::vector<ReceivedCorrection> out(std::make_move_iterator(pending_.begin()),
                                        std::make_move_iterator(pending_.end()));
    pending_.clear();
    return out;
  }

  void set_callback(CorrectionCallback callback) {
    const std::lock_guard callback_lock(callback_mutex_);
    callback_ = std::move(callback);
  }

  VehicleClientStats stats() const {
    const std::lock_guard lock(mutex_);
    VehicleClientStats out = stats_;
    out.corrections = filter_.counts();
    out.sequence_restarts = filter_.sequence_restarts();
    out.authentication = filter_.authentication_counts();
    return out;
  }

  udp::endpoint local_endpoint() const { return local_; }
  const std::vector<udp::endpoint>& rsu_endpoints() const { return rsus_; }
  std::uint32_t next_sequence() const {
    const std::lock_guard lock(mutex_);
    return announcer_.next_sequence();
  }

 private:
  std::string reply_address_for(const udp::endpoint& rsu) {
    if (!config_.reply_address.empty()) {
      if (!v2i::is_unicast_ip_literal(config_.reply_address)) {
        throw std::invalid_argument("reply address \"" + config_.reply_address +
                                    "\" is not a numeric unicast IP address");
      }
      return config_.reply_address;
    }
    if (!local_.address().is_unspecified()) {
      return local_.address().to_string();
    }
    // Bound to "any": ask the kernel which local address it would send to this RSU from (a connected
    // UDP socket sends nothing, it only picks the route).
    udp::socket probe(strand_);
    probe.open(rsu.protocol());
    boost::system::error_code ec;
    probe.connect(rsu, ec);
    if (ec) {
      throw std::invalid_argument("no route to RSU " + edge::to_text(rsu) + ": " + ec.message());
    }
    return probe.local_endpoint().address().to_string();
  }

  // Encodes one announcement per RSU with the next sequence number (Announcer). Caller holds mutex_.
  v2i::AnnouncementReason build(const VehicleState& state, std::vector<Outgoing>& out) {
    std::vector<std::vector<std::uint8_t>> datagrams;
    const v2i::AnnouncementReason reason = announcer_.announce(state, clock_(), reply_to_, datagrams);
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
      if (!datagrams[i].empty()) {
        out.push_back({rsus_[i], std::move(datagrams[i])});
      }
    }
    return reason;
  }

  // Posts the datagrams to the strand (never runs them inline, so callers may hold mutex_: they do, so
  // that datagrams leave in the order their sequence numbers were taken).
  void send(std::vector<Outgoing> outgoing, bool keepalive) {
    asio::post(strand_, [self = shared_from_this(), outgoing = std::move(outgoing), keepalive] {
      if (!self->socket_.is_open()) {
        return;  // stopped meanwhile
      }
      std::uint64_t sent = 0;
      std::uint64_t failed = 0;
      for (const Outgoing& o : outgoing) {
        boost::system::error_code ec;
        // A full send buffer (would_block) means the link is down: that datagram is lost, and counted.
        self->socket_.send_to(asio::buffer(o.bytes), o.destination, 0, ec);
        ec ? ++failed : ++sent;
      }
      const std::lock_guard lock(self->mutex_);
      self->stats_.announcements_sent += sent;
      self->stats_.send_errors += failed;
      if (keepalive && sent > 0) {
        ++self->stats_.keepalive_announcements;
      }
      self->last_sent_ = std::chrono::steady_clock::now();
    });
  }

  void arm_keepalive() {
    if (config_.announce_period <= 0) {
      return;
    }
    keepalive_.expires_after(std::chrono::nanoseconds(config_.announce_period));
    keepalive_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec == asio::error::operation_aborted) {
        return;
      }
      std::vector<Outgoing> outgoing;
      {
        const std::lock_guard lock(self->mutex_);
        if (self->stopped_) {
          return;
        }
        self->filter_.expire(self->clock_());
        // "Quiet" on the monotonic clock: a step of the common clock must not stop or flood repeats.
        const TimeNs quiet = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::steady_clock::now() - self->last_sent_)
                                 .count();
        if (const auto due = self->announcer_.keepalive_due(quiet, self->clock_())) {
          self->build(*due, outgoing);
        }
        if (!outgoing.empty()) {
          self->send(std::move(outgoing), true);  // in sequence order, as announce()
        }
      }
      self->arm_keepalive();
    });
  }

  void receive_next() {
    socket_.async_receive_from(
        asio::buffer(buffer_), sender_,
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t bytes) {
          self->on_receive(ec, bytes);
        });
  }

  void on_receive(const boost::system::error_code& ec, std::size_t bytes) {
    if (ec == asio::error::operation_aborted || !socket_.is_open()) {
      return;
    }
    std::optional<ReceivedCorrection> received;
    {
      const std::lock_guard lock(mutex_);
      if (stopped_) {
        return;
      }
      if (ec) {
        ++stats_.receive_errors;
      } else {
        ++stats_.datagrams_received;
        v2i::Correction correction;
        const CorrectionVerdict verdict = filter_.check({buffer_.data(), bytes}, clock_(), correction);
        if (verdict == CorrectionVerdict::kRefusal) {
          stats_.refusals.add(filter_.last_refusal().reason);
          stats_.last_refusal = ReceivedRefusal{filter_.last_refusal(), clock_(), edge::to_text(sender_)};
        }
        if (verdict == CorrectionVerdict::kFixWithheld) {
          stats_.fixes_withheld.add(filter_.last_fix_withheld().reason);
          stats_.last_fix_withheld =
              ReceivedFixWithheld{filter_.last_fix_withheld(), clock_(), edge::to_text(sender_)};
        }
        if (verdict == CorrectionVerdict::kAdvertisement) {
          stats_.advertisements.add(filter_.last_advertisement().fixes_withheld);
          stats_.last_advertisement =
              ReceivedAdvertisement{filter_.last_advertisement(), clock_(), edge::to_text(sender_)};
        }
        if (verdict == CorrectionVerdict::kAccepted) {
          received = ReceivedCorrection{std::move(correction), clock_(), edge::to_text(sender_)};
          pending_.push_back(*received);
          while (pending_.size() > std::max<std::size_t>(config_.max_pending_corrections, 1)) {
            pending_.pop_front();
            ++stats_.dropped_unpolled;
          }
        }
      }
    }
    if (received) {
      const std::lock_guard callback_lock(callback_mutex_);
      if (callback_) {
        callback_(*received);
      }
    }
    receive_next();
  }

  asio::strand<asio::io_context::executor_type> strand_;
  udp::socket socket_;            // used on strand_ only
  asio::steady_timer keepalive_;  // used on strand_ only
  const VehicleClientConfig config_;
  const Clock clock_;
  std::vector<udp::endpoint> rsus_;
  std::vector<v2i::UdpEndpoint> reply_to_;  // per RSU: the local address it reaches us at
  udp::endpoint local_;
  std::array<std::uint8_t, kReceiveBufferBytes> buffer_{};  // strand_ only
  udp::endpoint sender_;                                    // strand_ only

  mutable std::mutex mutex_;  // guards everything below
  bool stopped_ = false;
  vehicle::CorrectionFilter filter_;
  vehicle::Announcer announcer_;
  std::chrono::steady_clock::time_point last_sent_{};
  VehicleClientStats stats_;
  std::deque<ReceivedCorrection> pending_;

  std::recursive_mutex callback_mutex_;
  CorrectionCallback callback_;
};

VehicleClient::VehicleClient(asio::io_context& io, const VehicleClientConfig& config, Clock clock)
    : impl_(std::make_shared<Impl>(io, config, std::move(clock))) {
  impl_->start();
}

VehicleClient::~VehicleClient() {
  impl_->stop();
}

v2i::AnnouncementReason VehicleClient::announce(const VehicleState& state) {
  return impl_->announce(state);
}
std::vector<ReceivedCorrection> VehicleClient::poll() {
  return impl_->poll();
}
void VehicleClient::set_correction_callback(CorrectionCallback callback) {
  impl_->set_callback(std::move(callback));
}
VehicleClientStats VehicleClient::stats() const {
  return impl_->stats();
}
udp::endpoint VehicleClient::local_endpoint() const {
  return impl_->local_endpoint();
}
const std::vector<udp::endpoint>& VehicleClient::rsu_endpoints() const {
  return impl_->rsu_endpoints();
}
std::uint32_t VehicleClient::next_sequence() const {
  return impl_->next_sequence();
}
void VehicleClient::stop() {
  impl_->stop();
}

struct ThreadedVehicleClient::Loop {
  asio::io_context io;
  asio::executor_work_guard<asio::io_context::executor_type> work = asio::make_work_guard(io);
  std::thread thread;
};

ThreadedVehicleClient::ThreadedVehicleClient(const VehicleClientConfig& config, Clock clock)
    : loop_(std::make_unique<Loop>()),
      client_(std::make_unique<VehicleClient>(loop_->io, config, std::move(clock))) {
  loop_->thread = std::thread([loop = loop_.get()] { loop->io.run(); });
}

ThreadedVehicleClient::~ThreadedVehicleClient() {
  client_.reset();
  loop_->work.reset();
  // Pending handlers (the close posted by stop()) need not run: destroying the io_context frees them.
  loop_->io.stop();
  loop_->thread.join();
}

}  // namespace rsu::vehicle_client
