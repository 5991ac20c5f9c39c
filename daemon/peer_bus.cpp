// SPDX-License-Identifier: Apache-2.0
#include "daemon/peer_bus.h"

#include <spdlog/spdlog.h>

#include <sstream>

#include "ros/ros_time.h"

namespace rsu::daemon {

namespace {

// A V2I datagram is at most a UDP payload; anything longer is not one (and is not copied around).
constexpr std::size_t kMaxDatagramBytes = 65536;

}  // namespace

PeerBus::PeerBus(boost::asio::io_context& io, const dds::Participant& participant,
                 const PeerBusConfig& config, std::uint64_t rsu_id, BadInputLog& bad_input,
                 SharedHandler on_shared)
    : io_(io),
      rsu_id_(rsu_id),
      bad_input_(bad_input),
      on_shared_(std::move(on_shared)),
      topic_(participant, dds::ros_topic(config.topic), rsu_msgs_msg_dds__PeerAnnouncement__desc),
      writer_(participant, topic_, config.qos) {
  // The reader also gets this writer's samples: they are recognised by the writer's handle and dropped
  // undecoded. A sample with this RSU's id from another writer is a configuration error (rsu_id must
  // be unique on the bus): RsuCore counts it and the daemon reports it.
  dds::check(dds_get_instance_handle(writer_.handle(), &own_writer_), "reading the writer's handle");
  reader_ =
      std::make_unique<dds::Reader<Sample>>(participant, topic_, config.qos, [this] { on_data_available(); });
  spdlog::info("dds: sharing accepted announcements with the other RSUs on {}", topic_.name());
  on_data_available();  // samples that arrived before the listener was attached
}

PeerBus::~PeerBus() {
  reader_.reset();  // no listener call runs past this point
}

void PeerBus::share(std::span<const std::uint8_t> datagram, const core::SourceEndpoint& sender,
                    TimeNs received) {
  const ros::RosTime t = ros::to_ros_time(received);
  std::string address = sender.address;
  Sample s{};
  s.origin_rsu_id = rsu_id_;
  s.received_time = {t.sec, t.nanosec};
  s.sender_address = address.data();
  s.sender_port = sender.port;
  // Borrowed, not copied: Cyclone serializes the sample inside write().
  s.datagram._buffer = const_cast<std::uint8_t*>(datagram.data());
  s.datagram._length = static_cast<std::uint32_t>(datagram.size());
  s.datagram._maximum = s.datagram._length;
  s.datagram._release = false;
  try {
    writer_.write(s, received);
    ++shared_;
  } catch (const dds::DdsError& e) {
    ++share_failed_;
    bad_input_.report("peer_share", e.what());
  }
}

std::uint32_t PeerBus::peers() const {
  const std::uint32_t writers = reader_->matched_writers();
  return writers > 0 ? writers - 1 : 0;
}

void PeerBus::on_data_available() {
  if (!take_posted_.exchange(true))
    boost::asio::post(io_, [this] { take_samples(); });
}

void PeerBus::take_samples() {
  take_posted_.store(false);
  try {
    reader_->take(256, [this](const Sample& s, const dds_sample_info_t& info) {
      if (info.publication_handle == own_writer_)
        ++own_echoes_;
      else
        on_sample(s);
    });
  } catch (const dds::DdsError& e) {
    bad_input_.report("peer_take", e.what());
  }
}

void PeerBus::on_sample(const Sample& s) {
  ++received_;
  if (s.sender_address == nullptr || s.sender_address[0] == '\0' || s.sender_port == 0 ||
      s.datagram._length > kMaxDatagramBytes || (s.datagram._length > 0 && s.datagram._buffer == nullptr)) {
    ++received_malformed_;
    bad_input_.report("peer_sample", "from rsu " + std::to_string(s.origin_rsu_id) +
                                         ": no sender, or a datagram of " +
                                         std::to_string(s.datagram._length) + " bytes");
    return;
  }
  const core::PeerProvenance from{s.origin_rsu_id, {s.sender_address, s.sender_port}};
  on_shared_(std::span<const std::uint8_t>(s.datagram._buffer, s.datagram._length), from);
}

void PeerBus::report(CounterList& out) const {
  out.add("peer_bus", "shared", shared_);
  out.add("peer_bus", "share_failed", share_failed_);
  out.add("peer_bus", "own_echoes", own_echoes_);
  out.add("peer_bus", "received", received_);
  out.add("peer_bus", "received_malformed", received_malformed_);
  out.add_level("peer_bus", "peers", peers());
}

std::string PeerBus::stats_line() const {
  std::ostringstream s;
  s << "peer_bus: shared=" << shared_ << " share_failed=" << share_failed_ << " received=" << received_
    << " received_malformed=" << received_malformed_ << " peers=" << peers();
  return s.str();
}

}  // namespace rsu::daemon
