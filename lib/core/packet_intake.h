// SPDX-License-Identifier: Apache-2.0
// LiDAR packets into points in firing order: the configured sensor's decoder (lidar/lidar_decoder.h),
// the sensor's clock against the host's (lidar/sensor_clock.h: RsuCoreConfig::time_source and
// clock_tolerance), the reorder stage (lidar/packet_order.h) and load shedding
// (RsuCoreConfig::max_packet_age: a packet processed that late is dropped). The caller counts what is
// refused here (packet.clock_offset, packet.too_late).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/counter_list.h"
#include "common/time.h"
#include "core/rsu_core_config.h"
#include "lidar/lidar_decoder.h"
#include "lidar/packet_order.h"
#include "lidar/point.h"
#include "lidar/sensor_clock.h"

namespace rsu::core {

// The LiDAR's clock against the host's (lidar/sensor_clock.h), as the stats and the log report it.
struct SensorClockReport {
  bool known = false;    // a data packet has arrived
  TimeNs offset_ns = 0;  // host - sensor (transit included): positive when the sensor is behind
  bool beyond_tolerance = false;
};

struct PacketIntakeStep {
  lidar::PacketOutcome packet;  // what the decoder made of the payload
  // time_source sensor and the sensor's clock beyond the tolerance: a data packet refused.
  bool clock_refused = false;
  bool shed = false;  // a data packet dropped as too late
  // The first shed packet after packets that were used: what is open in the sweep now lacks the shed
  // points and must never be fitted as whole (the caller restarts its clustering).
  bool shedding_began = false;
};

class PacketIntake {
 public:
  // Throws std::invalid_argument naming the problem for an unknown model or unusable options.
  explicit PacketIntake(const RsuCoreConfig& config);

  // One UDP payload received at `now` (it resolves what the packet's own time leaves ambiguous): its
  // data points are queued for reordering unless shed.
  PacketIntakeStep push(std::span<const std::uint8_t> payload, TimeNs now);
  // The next packet's points in firing order (sensor frame) once due, or any held one if `drain`
  // (the end of the stream). False when none is.
  bool pop(std::vector<lidar::LidarPoint>& points, bool drain = false) { return order_.pop(points, drain); }

  const lidar::LidarDecoder& decoder() const { return *decoder_; }
  // Notices for the operator (log them once each, as warnings): the decoder's, and the sensor clock
  // crossing the tolerance (and what is then done).
  std::vector<std::string> take_notices();
  SensorClockReport sensor_clock() const;
  const lidar::PacketOrderStats& order_stats() const { return order_.stats(); }

  // This intake under `next` (SIGHUP): the decoder (its counters and measured rate) is kept when the
  // sensor is decoded the same way; the reorder stage and the shedding count start afresh.
  PacketIntake reloaded(const RsuCoreConfig& next) &&;

  // The decoder's counters: packet.<outcome> and decoder.<note> (the reorder stage's are in
  // lidar_stats.h).
  void report(CounterList& out) const;
  // The sensor clock (clock.offset_ms, clock.steps) and lidar.rotation_hz.
  void report_clock(CounterList& out) const;

 private:
  // Measures the clock on a data packet and says whether its points may be used (time_source sensor,
  // clock beyond the tolerance: no), queueing a notice when the clock crosses the tolerance.
  bool check_clock(const lidar::PacketOutcome& packet, TimeNs now);

  std::unique_ptr<lidar::LidarDecoder> decoder_;
  lidar::LidarDecoderOptions options_;
  std::string model_;
  lidar::PacketOrder order_;
  TimeNs max_packet_age_;
  TimeSource time_source_;
  TimeNs clock_tolerance_;
  lidar::SensorClock sensor_clock_;
  bool clock_beyond_ = false;
  std::vector<std::string> notices_;
  bool shedding_ = false;                   // the last data packet was shed
  std::vector<lidar::LidarPoint> scratch_;  // reused packet after packet
};

}  // namespace rsu::core
