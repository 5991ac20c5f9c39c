// SPDX-License-Identifier: Apache-2.0
// rsud's side of the bus the RSUs of a road share (README, "Several RSUs on one bus"; issue 6): every
// announcement rsud accepted from a vehicle over UDP is published on the peer-announcement topic with
// its provenance, the vehicle's datagram byte for byte; what the other RSUs publish there is handed to
// RsuCore::on_peer_announcement, which decodes, checks and registers it as the vehicle's own datagram.
//
// Threading (as daemon/dds_edge.h): Cyclone's data-available listener only posts one "take now" to
// rsud's io_context (coalesced by an atomic flag); samples are taken and handed on on that thread.
// Writes happen on that thread too, with best-effort QoS by default: a writer then never blocks rsud's
// only thread on a lagging peer, and a lost announcement is superseded by the vehicle's next one 100 ms
// later.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <boost/asio.hpp>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <span>
#include <string>

#include "common/counter_list.h"
#include "common/time.h"
#include "core/rsu_core.h"
#include "daemon/bad_input_log.h"
#include "daemon/config.h"
#include "dds/participant.h"
#include "dds/typed_entities.h"
#include "rsu_msgs.h"

namespace rsu::daemon {

class PeerBus {
 public:
  // A peer's announcement, on the io_context thread: the vehicle's datagram and where it came from.
  using SharedHandler =
      std::function<void(std::span<const std::uint8_t> datagram, const core::PeerProvenance& from)>;

  // Creates the topic, writer and reader on `participant` (which must outlive this). Throws
  // dds::DdsError with Cyclone's text.
  PeerBus(boost::asio::io_context& io, const dds::Participant& participant, const PeerBusConfig& config,
          std::uint64_t rsu_id, BadInputLog& bad_input, SharedHandler on_shared);
  ~PeerBus();
  PeerBus(const PeerBus&) = delete;
  PeerBus& operator=(const PeerBus&) = delete;

  // Publishes an announcement rsud accepted from `sender` over UDP at `received`.
  void share(std::span<const std::uint8_t> datagram, const core::SourceEndpoint& sender, TimeNs received);

  // Other RSUs' announcement writers currently matched (our own writer is matched too, not counted).
  std::uint32_t peers() const;

  // Its counters (the stats file and the metrics) and one log line.
  void report(CounterList& out) const;
  std::string stats_line() const;

 private:
  using Sample = rsu_msgs_msg_dds__PeerAnnouncement_;

  void on_data_available();  // Cyclone's thread
  void take_samples();       // io_context thread
  void on_sample(const Sample& sample);

  boost::asio::io_context& io_;
  std::uint64_t rsu_id_;
  BadInputLog& bad_input_;
  SharedHandler on_shared_;
  dds::Topic topic_;
  dds::Writer<Sample> writer_;
  dds_instance_handle_t own_writer_ = 0;
  std::atomic<bool> take_posted_{false};
  std::unique_ptr<dds::Reader<Sample>> reader_;  // last: deleted first (its listener posts)

  std::uint64_t shared_ = 0;
  std::uint64_t share_failed_ = 0;
  std::uint64_t own_echoes_ = 0;          // this RSU's own samples, delivered back by the bus
  std::uint64_t received_ = 0;            // from other RSUs' writers
  std::uint64_t received_malformed_ = 0;  // no sender address or port, or an oversized datagram
};

}  // namespace rsu::daemon
