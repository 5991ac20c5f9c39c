// SPDX-License-Identifier: Apache-2.0
// IPv4 fragment reassembly (RFC 791, RFC 815) for recorded traffic. A LiDAR datagram larger than the
// link MTU leaves the sensor as IP fragments, and a capture (tcpdump, Wireshark) records the fragments:
// every Ouster lidar packet (3 to 25 kB) does so on a 1500-byte Ethernet. pcap.cpp puts them back
// together before it hands out UDP datagrams.
//
// Fragments are keyed by (source, destination, protocol, identification). A datagram is complete when
// its last fragment (more-fragments clear) has arrived and every byte before it is covered. Refused,
// and counted: overlapping fragments whose bytes disagree (the whole datagram is dropped: no guessing
// which copy is right), fragments past the IPv4 maximum of 65,535 bytes, and datagrams still incomplete
// `timeout_ns` after their first fragment or evicted when more than `max_pending` are open.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "common/time.h"

namespace rsu::lidar {

struct Ipv4Fragment {
  std::uint32_t src = 0;  // host order
  std::uint32_t dst = 0;
  std::uint8_t protocol = 0;
  std::uint16_t identification = 0;
  std::size_t offset_bytes = 0;  // the header's fragment offset x 8
  bool more_fragments = false;
  std::span<const std::uint8_t> data;  // this fragment's part of the IP payload
  TimeNs time_ns = 0;                  // capture time
};

struct Ipv4Datagram {
  std::uint32_t src = 0;
  std::uint32_t dst = 0;
  std::uint8_t protocol = 0;
  TimeNs time_ns = 0;  // capture time of the fragment that completed it
  std::vector<std::uint8_t> payload;
};

struct ReassemblyStats {
  std::uint64_t fragments = 0;
  std::uint64_t reassembled = 0;
  std::uint64_t timed_out = 0;    // incomplete datagrams given up (timeout or eviction)
  std::uint64_t overlapping = 0;  // datagrams dropped for fragments that disagree
  std::uint64_t too_large = 0;    // fragments reaching past 65,535 bytes
};

class Ipv4Reassembler {
 public:
  // Throws std::invalid_argument unless timeout_ns > 0 and max_pending > 0.
  explicit Ipv4Reassembler(TimeNs timeout_ns = kNsPerSecond, std::size_t max_pending = 64);

  // The whole datagram when `fragment` completes one, nullopt otherwise.
  std::optional<Ipv4Datagram> add(const Ipv4Fragment& fragment);
  // Incomplete datagrams at the end of the input: given up, counted as timed out.
  void finish();

  const ReassemblyStats& stats() const { return stats_; }
  std::size_t pending() const { return pending_.size(); }

 private:
  using Key = std::tuple<std::uint32_t, std::uint32_t, std::uint8_t, std::uint16_t>;
  struct Pending {
    TimeNs first_ns = 0;
    std::vector<std::uint8_t> bytes;
    std::vector<bool> covered;         // per byte of `bytes`
    std::optional<std::size_t> total;  // known once the last fragment arrived
    std::size_t covered_count = 0;
  };

  void expire(TimeNs now);
  // Copies the fragment in; false if it disagrees with bytes already there.
  static bool merge(Pending& p, const Ipv4Fragment& f);

  TimeNs timeout_ns_;
  std::size_t max_pending_;
  std::map<Key, Pending> pending_;
  ReassemblyStats stats_;
};

}  // namespace rsu::lidar
