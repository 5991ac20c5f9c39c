// SPDX-License-Identifier: Apache-2.0
#include "tools/rsu_relay/relay.h"

#include <chrono>
#include <stdexcept>

#include "edge/address_text.h"
#include "io/text_file.h"

namespace rsu::tools {

namespace asio = boost::asio;
using udp = asio::ip::udp;

namespace {

TimeNs steady_now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::vector<ImpairedDirection> uplinks_for(const RelayConfig& c) {
  std::vector<ImpairedDirection> out;
  for (std::size_t i = 0; i < c.rsus.size(); ++i) {
    out.emplace_back(c.link[0], c.seed, i == 0 ? 0 : 1 + i);
  }
  return out;
}

}  // namespace

Relay::Relay(asio::io_context& io, const RelayConfig& config)
    : config_(config),
      timer_(io),
      uplinks_(uplinks_for(config)),
      downlink_(config.link[1], config.seed, 1),
      tamper_(config.tamper, config.rsu_key) {
  if (config_.listen.empty() || config_.listen.size() != config_.rsus.size()) {
    throw std::invalid_argument("give one --listen per --rsu");
  }
  std::vector<udp::endpoint> binds = config_.listen;
  binds.emplace_back(config_.rsu_side_address, config_.vehicle.port());
  for (const udp::endpoint& at : binds) {
    auto socket = std::make_unique<udp::socket>(io, at.protocol());
    socket->bind(at);
    socket->non_blocking(true);  // a full send buffer drops the datagram (counted), as a radio would
    sockets_.push_back(std::move(socket));
  }
  buffers_.resize(sockets_.size());
  senders_.resize(sockets_.size());
  if (!config_.tamper_log_path.empty()) {
    tamper_log_ = std::fopen(config_.tamper_log_path.c_str(), "w");
    if (tamper_log_ == nullptr) {
      throw std::runtime_error("--tamper-log: " + config_.tamper_log_path +
                               ": cannot open: " + io::errno_text());
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

RelayStats Relay::stats() const {
  RelayStats out = stats_;
  for (const ImpairedDirection& up : uplinks_) {
    const ImpairedDirectionStats& s = up.stats();
    out.direction[0].received += s.received;
    out.direction[0].dropped += s.dropped;
    out.direction[0].reordered += s.reordered;
    out.direction[0].forwarded += s.forwarded;
  }
  out.direction[1] = downlink_.stats();
  return out;
}

std::string Relay::describe() const {
  std::string text;
  for (std::size_t i = 0; i < config_.listen.size(); ++i) {
    text += (i ? ", " : "") + edge::to_text(config_.listen[i]) + " -> " + edge::to_text(config_.rsus[i]);
  }
  return text + "; corrections at " + edge::to_text(sockets_.back()->local_endpoint()) + " -> " +
         edge::to_text(config_.vehicle);
}

void Relay::receive(std::size_t i) {
  sockets_[i]->async_receive_from(asio::buffer(buffers_[i]), senders_[i],
                                  [this, i](const boost::system::error_code& ec, std::size_t bytes) {
                                    if (ec == asio::error::operation_aborted) {
                                      return;
                                    }
                                    if (!ec) {
                                      std::vector<std::uint8_t> datagram(buffers_[i].begin(),
                                                                         buffers_[i].begin() + bytes);
                                      if (i + 1 < sockets_.size()) {
                                        uplinks_[i].push(steady_now(), std::move(datagram));
                                      } else {
                                        on_correction_side(std::move(datagram), steady_now());
                                      }
                                      flush();
                                    }
                                    receive(i);
                                  });
}

void Relay::on_correction_side(std::vector<std::uint8_t> bytes, TimeNs now) {
  TamperedDatagram t = tamper_.process(bytes);
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
  downlink_.push(now, std::move(t.bytes));
}

// Sends what is due in every direction and waits for the next due time.
void Relay::flush() {
  const TimeNs now = steady_now();
  std::optional<TimeNs> next;
  const auto note = [&](const std::optional<TimeNs>& due) {
    if (due && (!next || *due < *next)) {
      next = due;
    }
  };
  for (std::size_t i = 0; i < uplinks_.size(); ++i) {
    for (const auto& bytes : uplinks_[i].pop_due(now)) {
      send(*sockets_.back(), bytes, config_.rsus[i], 0);
    }
    note(uplinks_[i].next_due());
  }
  for (const auto& bytes : downlink_.pop_due(now)) {
    send(*sockets_.front(), bytes, config_.vehicle, 1);
  }
  note(downlink_.next_due());
  if (!next) {
    return;
  }
  timer_.expires_after(std::chrono::nanoseconds(std::max<TimeNs>(0, *next - now)));
  timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) {
      flush();
    }
  });
}

void Relay::send(udp::socket& from, const std::vector<std::uint8_t>& bytes, const udp::endpoint& to,
                 int direction) {
  boost::system::error_code ec;
  from.send_to(asio::buffer(bytes), to, 0, ec);
  stats_.send_errors[static_cast<std::size_t>(direction)] += ec ? 1 : 0;
}

}  // namespace rsu::tools
