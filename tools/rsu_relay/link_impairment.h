// What an impaired radio link does to one datagram (rsu-relay): lose it, delay it by a fixed latency
// plus jitter, or hold it back so that the next one overtakes it (reordering, as `rsu-sim stream
// --reorder` does for LiDAR packets). Every decision is drawn from a counter-based random stream keyed by
// (seed, direction, datagram index), so a seed repeats a run exactly whatever the timing. Pure.
#pragma once

#include <cstdint>

#include "common/time.h"

namespace rsu::tools {

struct LinkImpairment {
  double delay_ms = 0.0;   // added to every datagram
  double jitter_ms = 0.0;  // plus a uniform draw within [-jitter, +jitter] (never below 0 in total)
  double loss = 0.0;       // fraction of datagrams dropped, [0, 1)
  double reorder = 0.0;    // fraction held back and sent after the next one, [0, 1)

  bool any() const { return delay_ms > 0.0 || jitter_ms > 0.0 || loss > 0.0 || reorder > 0.0; }
};

struct LinkDecision {
  bool drop = false;
  bool hold_for_next = false;  // sent after the next datagram of the same direction
  TimeNs delay = 0;            // from arrival at the relay to sending
};

// Datagram `index` (0, 1, ... per direction) of direction `direction` (0 uplink, 1 downlink).
LinkDecision decide(const LinkImpairment& link, std::uint64_t seed, std::uint64_t direction,
                    std::uint64_t index);

}  // namespace rsu::tools
