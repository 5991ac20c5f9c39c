// SPDX-License-Identifier: Apache-2.0
// Puts a Velodyne packet stream back in time order and counts what the network did to it (issue 7:
// LiDAR packet loss and reordering). Velodyne data packets carry no sequence number, only the time of
// their first firing (docs/design.md §2); consecutive packets are one packet period apart (12 blocks:
// VLP-16 1327.104 us, VLP-32C 663.552 us), so that time is the sequence:
//   - a packet earlier than the newest one is REORDERED: held packets (up to `depth`) are released in
//     time order, so a packet at most `depth` places late is put back; one later than that arrives
//     after its place was released and is dropped (LATE), as the sweep clusterer needs firing order
//     (sweep_clusterer.h: time going backwards would restart it, dropping every pending point);
//   - a packet with the time of one already taken is a DUPLICATE, dropped;
//   - between two released packets, every missing period is a LOST packet (late ones included: their
//     place was empty when released), counted from when the earlier one said its successor was due
//     (lidar_decoder.h: PacketOutcome::next_ns; past a field-of-view gap, not one period later);
//   - a jump of more than `max_gap_ns` either way is the stream STOPPING or restarting (a sensor
//     power cycle, a cable), not loss: the order restarts from that packet.
// Holding packets delays every point by `depth` packet periods, so the depth is 0 by default: a LiDAR
// on its own Ethernet link does not reorder; a switched network may (then e.g. 3: 2 ms on a VLP-32C).
// Pure: times are the packets' own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "common/time.h"
#include "lidar/point.h"

namespace rsu::lidar {

struct PacketOrderConfig {
  std::size_t depth = 0;  // packets held to put late ones back in order (file comment)
};

struct PacketOrderStats {
  std::uint64_t released = 0;
  std::uint64_t reordered = 0;    // arrived after a later packet, put back in order
  std::uint64_t late = 0;         // arrived after its place was released: dropped
  std::uint64_t duplicate = 0;    // same first-firing time as a packet already taken: dropped
  std::uint64_t lost = 0;         // missing packet periods between released packets
  std::uint64_t stream_gaps = 0;  // the stream stopped or jumped (more than max_gap_ns): restarted
};

class PacketOrder {
 public:
  // `packet_period_ns`: the sensor's packet period (FiringSchedule::packet_period_ns). `max_gap_ns`:
  // a longer silence or jump back is a restart of the stream. Throws std::invalid_argument if either
  // is not positive.
  PacketOrder(const PacketOrderConfig& config, TimeNs packet_period_ns, TimeNs max_gap_ns);

  // One packet: its first firing time, when its successor is due (0: one packet period later) and its
  // points (copied). Returns false if it was dropped (late or duplicate).
  bool push(TimeNs first_firing_ns, std::span<const LidarPoint> points, TimeNs next_due_ns = 0);
  // The next packet in time order once more than `depth` are held, or any held one if `everything`
  // (the end of the stream). Its points replace `out`'s content. False when none is due.
  bool pop(std::vector<LidarPoint>& out, bool everything = false);

  // The sensor's packet period as it changes (a dual-return stream's packets span half the time).
  // Ignored unless positive.
  void set_packet_period(TimeNs packet_period_ns) {
    if (packet_period_ns > 0)
      period_ns_ = packet_period_ns;
  }

  std::size_t held() const { return held_.size(); }
  const PacketOrderStats& stats() const { return stats_; }

 private:
  struct Held {
    TimeNs time = 0;
    TimeNs next_due = 0;
    std::vector<LidarPoint> points;
  };
  void count_gap(TimeNs previous_next_due, TimeNs next);

  PacketOrderConfig config_;
  TimeNs period_ns_;
  TimeNs max_gap_ns_;
  std::deque<Held> held_;                       // sorted by time
  std::vector<std::vector<LidarPoint>> spare_;  // released buffers, reused
  bool released_any_ = false;
  TimeNs last_released_ = 0;
  TimeNs last_released_next_due_ = 0;
  TimeNs newest_ = 0;  // newest time pushed
  PacketOrderStats stats_;
};

}  // namespace rsu::lidar
