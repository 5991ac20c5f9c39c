#include "tools/rsu_relay/relay.h"

#include <stdexcept>

#include "vehicle_client/udp_endpoint_text.h"

namespace rsu::tools {

namespace asio = boost::asio;
using udp = asio::ip::udp;

Relay::Relay(asio::io_context& io, const RelayConfig& config)
    : io_(io), config_(config), timer_(io), tamper_(config.tamper, config.rsu_key) {
  if (config_.listen.empty() || config_.listen.size() != config_.rsus.size()) {
    throw std::invalid_argument("give one --listen per --rsu");
  }
  std::vector<udp::endpoint> binds = config_.listen;
  binds.emplace_back(config_.rsu_side_address, config_.vehicle.port());
  for (const udp::endpoint& at : binds) {
    auto socket = std::make_unique<udp::socket>(io_, at.protocol());
    socket->bind(at);
    socket->non_blocking(true);  // a full send buffer drops the datagram (counted), as a radio would
    sockets_.push_back(std::move(socket));
  }
  buffers_.resize(sockets_.size());
  senders_.resize(sockets_.size());
  if (!config_.tamper_log_path.empty()) {
    tamper_log_ = std::fopen(config_.tamper_log_path.c_str(), "w");
    if (tamper_log_ == nullptr) {
      throw std::runtime_error("cannot write --tamper-log \"" + config_.tamper_log_path + "\"");
    }
    std::fprintf(tamper_log_, "sweep_time_ns,rsu_id,sequence,altered,burst,x,y,cxx,cyy\n");
  }
  for (std::size_t i = 0; i < sockets_.size(); ++i) {
    receive(i);
  }
}

Relay::~Relay() {
  if (tamper_log_ != nullptr) {
    std::fclose(tamper_log_);
  }
}

std::string Relay::describe() const {
  std::string text;
  for (std::size_t i = 0; i < config_.listen.size(); ++i) {
    text += (i ? ", " : "") + vehicle_client::to_text(config_.listen[i]) + " -> " +
            vehicle_client::to_text(config_.rsus[i]);
  }
  return text + "; corrections at " + vehicle_client::to_text(sockets_.back()->local_endpoint()) + " -> " +
         vehicle_client::to_text(config_.vehicle);
}

void Relay::receive(std::size_t i) {
  sockets_[i]->async_receive_from(asio::buffer(buffers_[i]), senders_[i],
                                  [this, i](const boost::system::error_code& ec, std::size_t bytes) {
                                    if (ec == asio::error::operation_aborted) {
                                      return;
                                    }
                                    if (!ec) {
                                      on_datagram(i, {buffers_[i].begin(), buffers_[i].begin() + bytes});
                                    }
                                    receive(i);
                                  });
}

void Relay::on_datagram(std::size_t i, std::vector<std::uint8_t> bytes) {
  const bool uplink = i + 1 < sockets_.size();
  const int direction = uplink ? 0 : 1;
  ++stats_.direction[direction].received;
  Pending pending{Clock::now(), uplink ? config_.rsus[i] : config_.vehicle, std::move(bytes), direction};
  if (!uplink) {
    TamperedDatagram t = tamper_.process(pending.bytes);
    if (t.correction) {
      ++stats_.corrections;
      stats_.corrections_altered += t.altered ? 1 : 0;
      stats_.corrections_burst += t.burst ? 1 : 0;
      if (tamper_log_ != nullptr) {
        const v2i::Correction& c = *t.correction;
        std::fprintf(tamper_log_, "%lld,%llu,%u,%d,%d,%.6f,%.6f,%.9g,%.9g\n",
                     static_cast<long long>(c.sweep_time), static_cast<unsigned long long>(c.rsu_id),
                     c.sequence, t.altered ? 1 : 0, t.burst ? 1 : 0, c.pose.x, c.pose.y,
                     c.pose_covariance(0, 0), c.pose_covariance(1, 1));
        std::fflush(tamper_log_);
      }
    }
    pending.bytes = std::move(t.bytes);
  }
  const LinkDecision d = decide(config_.link[direction], config_.seed, direction, index_[direction]++);
  if (d.drop) {
    ++stats_.direction[direction].dropped;
    return;
  }
  pending.at += std::chrono::nanoseconds(d.delay);
  schedule(std::move(pending), d.hold_for_next);
}

void Relay::schedule(Pending pending, bool hold_for_next) {
  const int direction = pending.direction;
  if (hold_for_next && !held_[direction]) {
    held_[direction] = std::move(pending);  // goes out after the next one of its direction
    arm_timer();
    return;
  }
  const Clock::time_point at = pending.at;
  queue_.emplace(at, std::move(pending));
  if (held_[direction]) {
    Pending overtaken = std::move(*held_[direction]);
    held_[direction].reset();
    overtaken.at = std::max(overtaken.at, at + std::chrono::microseconds(1));
    ++stats_.direction[direction].reordered;
    queue_.emplace(overtaken.at, std::move(overtaken));
  }
  arm_timer();
}

void Relay::arm_timer() {
  std::optional<Clock::time_point> next;
  if (!queue_.empty()) {
    next = queue_.begin()->first;
  }
  for (const auto& held : held_) {
    if (held) {
      const Clock::time_point deadline = held->at + config_.reorder_timeout;
      next = next ? std::min(*next, deadline) : deadline;
    }
  }
  if (!next) {
    return;
  }
  timer_.expires_at(*next);
  timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec != asio::error::operation_aborted) {
      on_timer();
    }
  });
}

void Relay::on_timer() {
  const Clock::time_point now = Clock::now();
  while (!queue_.empty() && queue_.begin()->first <= now) {
    send(queue_.begin()->second);
    queue_.erase(queue_.begin());
  }
  for (auto& held : held_) {
    if (held && held->at + config_.reorder_timeout <= now) {
      send(*held);  // nothing overtook it: late, but in order
      held.reset();
    }
  }
  arm_timer();
}

void Relay::send(const Pending& pending) {
  boost::system::error_code ec;
  sockets_.back()->send_to(asio::buffer(pending.bytes), pending.to, 0, ec);
  ec ? ++stats_.direction[pending.direction].send_errors : ++stats_.direction[pending.direction].forwarded;
}

}  // namespace rsu::tools
