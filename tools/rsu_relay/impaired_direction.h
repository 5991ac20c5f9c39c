// SPDX-License-Identifier: Apache-2.0
// One direction of an impaired radio link (rsu-relay): what happens to each datagram and when it
// leaves. A datagram is lost with probability `loss`; otherwise it leaves `delay_ms` plus a uniform
// jitter within +-`jitter_ms` (never before it arrived) after it came, so that with jitter a later
// datagram can overtake an earlier one; a share `reorder` of them is held back and leaves right after the
// next datagram of this direction (or `reorder_timeout` after its own time if none comes), as a radio
// link's retransmissions and a kernel's netem do. Every draw comes from a counter-based random stream
// keyed by (seed, direction, datagram index), so a seed repeats a run's decisions whatever the timing.
// Pure: the caller passes the time in and sends what pop_due returns.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "common/time.h"

namespace rsu::tools {

struct LinkImpairment {
  double delay_ms = 0.0;
  double jitter_ms = 0.0;
  double loss = 0.0;     // [0, 1)
  double reorder = 0.0;  // [0, 1)
};

struct ImpairedDirectionStats {
  std::uint64_t received = 0, dropped = 0, reordered = 0, forwarded = 0;
};

class ImpairedDirection {
 public:
  using Datagram = std::vector<std::uint8_t>;

  // direction: any number naming the direction (its own random stream), e.g. 0 uplink, 1 downlink.
  ImpairedDirection(const LinkImpairment& link, std::uint64_t seed, std::uint64_t direction,
                    TimeNs reorder_timeout = 100 * kNsPerMs);

  // A datagram arrived at `now`.
  void push(TimeNs now, Datagram bytes);
  // The datagrams due by `now`, in the order they leave; counted as forwarded.
  std::vector<Datagram> pop_due(TimeNs now);
  // When the next datagram is due (empty: nothing waits).
  std::optional<TimeNs> next_due() const;

  const ImpairedDirectionStats& stats() const { return stats_; }

 private:
  // Due time, then arrival order: datagrams due at the same time leave in the order they were queued.
  using Key = std::pair<TimeNs, std::uint64_t>;
  struct Held {
    TimeNs due = 0;
    Datagram bytes;
  };

  double draw(std::uint64_t kind) const;
  void enqueue(TimeNs due, Datagram bytes);

  LinkImpairment link_;
  std::uint64_t seed_;
  std::uint64_t direction_;
  TimeNs reorder_timeout_;
  std::uint64_t index_ = 0;  // datagrams received so far: the random streams' counter
  std::uint64_t order_ = 0;  // queue insertion order
  std::map<Key, Datagram> queue_;
  std::optional<Held> held_;  // waiting for the next datagram to overtake it
  ImpairedDirectionStats stats_;
};

}  // namespace rsu::tools
