// SPDX-License-Identifier: Apache-2.0
// The offset between a LiDAR's clock and the host's, measured on every data packet (issue 11: sensor
// time). A packet leaves the sensor after its last firing, so arrival - end of the packet (on the
// sensor clock) = clock offset + transit and queueing delay. The delays only add, so the estimate is
// the smallest such value seen, allowed to creep up by the drift two free-running crystal clocks can
// have (100 ppm) so that it follows a slowly drifting sensor clock; a jump of more than
// `step_threshold` either way (the sensor's clock was set, or restarted from zero) starts the estimate
// afresh. A host that falls behind (packets queued in its socket) raises the raw value but not the
// estimate: the lag stays visible as raw - estimate.
//
// Stamping by arrival (time_source host_receive) moves the sensor's times by an offset that must not
// jump: a new smallest delay lowers the estimate at once, and moving the points by that step could put
// a packet before its predecessor. So the stamping offset follows the estimate at no more than
// `max_slew` of the sensor time passing (1 %: a rotation's internal timing distorted by at most 1 ms
// while it converges), except across a clock step.
// Pure: the caller passes both times in.
#pragma once

#include <cstdint>
#include <optional>

#include "common/time.h"

namespace rsu::lidar {

struct SensorClockConfig {
  double max_drift = 1e-4;                    // s/s the estimate may rise by
  double max_slew = 1e-2;                     // s/s the stamping offset may move by
  TimeNs step_threshold = 10 * kNsPerSecond;  // a larger change is a new clock, not drift or lag
};

class SensorClock {
 public:
  explicit SensorClock(const SensorClockConfig& config = {});

  // One data packet: the end of its firings on the sensor's clock, its arrival on the host's.
  void observe(TimeNs sensor_end_ns, TimeNs arrival_ns);

  // host - sensor: add to a sensor time to get host time. nullopt before the first packet.
  std::optional<TimeNs> offset_ns() const { return known_ ? std::optional<TimeNs>(estimate_) : std::nullopt; }
  // The offset to stamp points with (file comment): the estimate, approached without jumps.
  TimeNs stamping_offset_ns() const { return stamping_; }
  // The last packet's arrival - end: the offset plus that packet's delay.
  TimeNs last_raw_ns() const { return last_raw_; }
  std::uint64_t steps() const { return steps_; }  // times the estimate started afresh

 private:
  SensorClockConfig config_;
  bool known_ = false;
  TimeNs estimate_ = 0;
  TimeNs last_raw_ = 0;
  TimeNs last_arrival_ = 0;
  TimeNs last_sensor_ = 0;
  TimeNs stamping_ = 0;
  std::uint64_t steps_ = 0;
};

}  // namespace rsu::lidar
