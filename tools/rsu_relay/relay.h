// rsu-relay's event loop: UDP datagrams between a vehicle and its RSUs on loopback, each direction
// impaired (LinkImpairment), corrections altered on the way down (CorrectionTamper). Boost.Asio, one
// thread.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tools/rsu_relay/correction_tamper.h"
#include "tools/rsu_relay/link_impairment.h"

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
  // A held-back datagram goes out after this long if no later one overtook it.
  std::chrono::milliseconds reorder_timeout{100};
  TamperConfig tamper;
  std::optional<v2i::security::SigningKey> rsu_key;
  std::string tamper_log_path;  // CSV of every correction forwarded (empty: none)
};

struct DirectionStats {
  std::uint64_t received = 0, forwarded = 0, dropped = 0, reordered = 0, send_errors = 0;
};

struct RelayStats {
  std::array<DirectionStats, 2> direction;
  std::uint64_t corrections = 0, corrections_altered = 0, corrections_burst = 0;
};

class Relay {
 public:
  Relay(boost::asio::io_context& io, const RelayConfig& config);
  ~Relay();
  Relay(const Relay&) = delete;
  Relay& operator=(const Relay&) = delete;

  const RelayStats& stats() const { return stats_; }
  std::string describe() const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Pending {
    Clock::time_point at;
    boost::asio::ip::udp::endpoint to;
    std::vector<std::uint8_t> bytes;
    int direction = 0;
  };

  void receive(std::size_t socket_index);
  void on_datagram(std::size_t socket_index, std::vector<std::uint8_t> bytes);
  void schedule(Pending pending, bool hold_for_next);
  void arm_timer();
  void on_timer();
  void send(const Pending& pending);

  boost::asio::io_context& io_;
  RelayConfig config_;
  std::vector<std::unique_ptr<boost::asio::ip::udp::socket>> sockets_;  // vehicle side ..., then RSU side
  std::vector<std::array<std::uint8_t, 65536>> buffers_;
  std::vector<boost::asio::ip::udp::endpoint> senders_;
  boost::asio::steady_timer timer_;
  std::multimap<Clock::time_point, Pending> queue_;
  std::array<std::optional<Pending>, 2> held_;
  std::array<std::uint64_t, 2> index_{};
  CorrectionTamper tamper_;
  std::FILE* tamper_log_ = nullptr;
  RelayStats stats_;
};

}  // namespace rsu::tools
