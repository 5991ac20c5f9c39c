// SPDX-License-Identifier: Apache-2.0
// rsu-relay's event loop: UDP datagrams between a vehicle and its RSUs on loopback, each direction
// impaired (ImpairedDirection), corrections altered on the way down (CorrectionTamper). Boost.Asio, one
// thread.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tools/rsu_relay/correction_tamper.h"
#include "tools/rsu_relay/impaired_direction.h"

namespace rsu::tools {

struct RelayConfig {
  std::vector<boost::asio::ip::udp::endpoint> listen;  // per RSU: where the vehicle's announcements come in
  std::vector<boost::asio::ip::udp::endpoint> rsus;    // ... and where they go
  boost::asio::ip::udp::endpoint vehicle;              // where the vehicle receives corrections
  // The relay's RSU side: bound at this address and the vehicle's port, announcements leave from it and
  // corrections come back to it (the vehicle announces this address as its reply address).
  boost::asio::ip::address rsu_side_address;
  std::array<LinkImpairment, 2> link;  // [0] uplink (vehicle -> RSU), [1] downlink (RSU -> vehicle)
  std::uint64_t seed = 1;
  TamperConfig tamper;
  std::optional<v2i::security::SigningKey> rsu_key;
  std::string tamper_log_path;  // CSV of every correction forwarded (empty: none)
};

struct RelayStats {
  std::array<ImpairedDirectionStats, 2> direction;  // [0] uplink (all RSUs), [1] downlink
  std::array<std::uint64_t, 2> send_errors{};
  std::uint64_t corrections = 0, corrections_altered = 0, corrections_burst = 0;
};

class Relay {
 public:
  Relay(boost::asio::io_context& io, const RelayConfig& config);
  ~Relay();
  Relay(const Relay&) = delete;
  Relay& operator=(const Relay&) = delete;

  RelayStats stats() const;
  std::string describe() const;

 private:
  void receive(std::size_t socket_index);
  void on_correction_side(std::vector<std::uint8_t> bytes, TimeNs now);
  void flush();
  void send(boost::asio::ip::udp::socket& from, const std::vector<std::uint8_t>& bytes,
            const boost::asio::ip::udp::endpoint& to, int direction);

  RelayConfig config_;
  std::vector<std::unique_ptr<boost::asio::ip::udp::socket>> sockets_;  // vehicle side ..., then RSU side
  std::vector<std::array<std::uint8_t, 65536>> buffers_;
  std::vector<boost::asio::ip::udp::endpoint> senders_;
  boost::asio::steady_timer timer_;
  // One uplink per RSU (its random stream: 0 for the first, as the downlink's is 1; 2, 3, ... for more).
  std::vector<ImpairedDirection> uplinks_;
  ImpairedDirection downlink_;
  CorrectionTamper tamper_;
  std::FILE* tamper_log_ = nullptr;
  RelayStats stats_;
};

}  // namespace rsu::tools
