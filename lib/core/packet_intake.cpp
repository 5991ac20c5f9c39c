// SPDX-License-Identifier: Apache-2.0
#include "core/packet_intake.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace rsu::core {
namespace {

// The packet stream's order rule: the sensor's packet period, and a silence as long as the sweep
// clusterer's restart rule (perception::SweepConfig::max_gap_rotations) is a restart of the stream.
lidar::PacketOrder packet_order_for(const RsuCoreConfig& config, const lidar::SweepGeometry& geometry) {
  const auto max_gap = static_cast<TimeNs>(config.sweep.max_gap_rotations / geometry.rotation_hz * 1e9);
  return lidar::PacketOrder(config.packet_order, geometry.packet_period_ns, std::max<TimeNs>(1, max_gap));
}

// "52.312 s behind" / "0.8 ms ahead of": how the sensor's clock stands to the host's (offset = host -
// sensor).
std::string describe_clock_offset(TimeNs offset_ns) {
  const double magnitude = std::abs(static_cast<double>(offset_ns));
  char amount[48];
  if (magnitude >= 1e9)
    std::snprintf(amount, sizeof amount, "%.3f s", magnitude * 1e-9);
  else
    std::snprintf(amount, sizeof amount, "%.1f ms", magnitude * 1e-6);
  return std::string(amount) + (offset_ns >= 0 ? " behind" : " ahead of");
}

}  // namespace

PacketIntake::PacketIntake(const RsuCoreConfig& config)
    : decoder_(lidar::make_lidar_decoder(config.sensor_model, config.sensor_options)),
      options_(config.sensor_options),
      model_(config.sensor_model),
      order_(packet_order_for(config, decoder_->geometry())),
      max_packet_age_(config.max_packet_age),
      time_source_(config.time_source),
      clock_tolerance_(config.clock_tolerance) {}

PacketIntakeStep PacketIntake::push(std::span<const std::uint8_t> payload, TimeNs now) {
  scratch_.clear();
  PacketIntakeStep step;
  step.packet = decoder_->decode(payload, now, scratch_);
  if (!step.packet.is_data())
    return step;  // counted by the decoder, by kind and reason
  order_.set_packet_period(decoder_->geometry().packet_period_ns);
  if (!check_clock(step.packet, now)) {
    step.clock_refused = true;
    return step;
  }
  if (time_source_ == TimeSource::kHostReceive) {
    // On the host clock: the packet's sensor times moved by the measured offset (its arrival minus its
    // known duration, the smallest delay seen, approached without jumps: sensor_clock.h); relative
    // times stay the sensor's.
    const TimeNs shift = sensor_clock_.stamping_offset_ns();
    for (lidar::LidarPoint& p : scratch_)
      p.time_ns += shift;
    step.packet.first_ns += shift;
    step.packet.next_ns += shift;
  }
  if (max_packet_age_ > 0 && now - step.packet.first_ns > max_packet_age_) {
    // Behind (an overload, a stall): shed, so that the RSU catches up (RsuCoreConfig::max_packet_age).
    step.shed = true;
    step.shedding_began = !shedding_;
    shedding_ = true;
    return step;
  }
  shedding_ = false;
  order_.push(step.packet.first_ns, scratch_, step.packet.next_ns);  // a late one is counted
  return step;
}

bool PacketIntake::check_clock(const lidar::PacketOutcome& packet, TimeNs now) {
  sensor_clock_.observe(packet.next_ns, now);
  const TimeNs offset = *sensor_clock_.offset_ns();
  const bool beyond = std::abs(static_cast<double>(offset)) > static_cast<double>(clock_tolerance_);
  const bool sensor_time = time_source_ == TimeSource::kSensor;
  if (beyond != clock_beyond_) {
    clock_beyond_ = beyond;
    const std::string where = "the LiDAR's clock is " + describe_clock_offset(offset) + " the host's";
    const std::string tolerance = std::to_string(clock_tolerance_ / kNsPerMs) + " ms";
    if (beyond && sensor_time) {
      notices_.push_back(where + " (beyond lidar.clock_tolerance_ms, " + tolerance +
                         "): its packets are REFUSED (packet.clock_offset) while this lasts. Synchronise the "
                         "LiDAR to the RSU's clock (PTP or GNSS PPS), or set lidar.time_source: host_receive "
                         "to stamp its points by arrival");
    } else if (beyond) {
      notices_.push_back(
          where + " (beyond " + tolerance +
          "): lidar.time_source host_receive stamps its points by arrival, the offset removed");
    } else {
      notices_.push_back(where + ": within lidar.clock_tolerance_ms (" + tolerance + ") again" +
                         (sensor_time ? ", its packets are used" : ""));
    }
  }
  return !(beyond && sensor_time);
}

std::vector<std::string> PacketIntake::take_notices() {
  std::vector<std::string> out = decoder_->take_notices();
  for (std::string& n : notices_)
    out.push_back(std::move(n));
  notices_.clear();
  return out;
}

SensorClockReport PacketIntake::sensor_clock() const {
  SensorClockReport r;
  if (const auto offset = sensor_clock_.offset_ns()) {
    r.known = true;
    r.offset_ns = *offset;
    r.beyond_tolerance = clock_beyond_;
  }
  return r;
}

PacketIntake PacketIntake::reloaded(const RsuCoreConfig& next) && {
  PacketIntake fresh(next);
  if (model_ == next.sensor_model && options_ == next.sensor_options)
    fresh.decoder_ = std::move(decoder_);  // its counters and measured rate go on
  return fresh;
}

void PacketIntake::report(CounterList& out) const {
  // The decoder's outcomes as packet.<outcome>, its informational counts as decoder.<name>.
  for (const auto& [name, value] : decoder_->counters()) {
    if (name.starts_with("note."))
      out.add("decoder", std::string_view(name).substr(5), value);
    else
      out.add("packet", name, value);
  }
}

void PacketIntake::report_clock(CounterList& out) const {
  // host - sensor, transit included (NaN before any packet); steps: jumps of the sensor's clock.
  const auto offset = sensor_clock_.offset_ns();
  out.add_measured("clock", "offset_ms", offset ? static_cast<double>(*offset) * 1e-6 : std::nan(""));
  out.add("clock", "steps", sensor_clock_.steps());
  out.add_measured("lidar", "rotation_hz", decoder_->geometry().rotation_hz);
}

}  // namespace rsu::core
