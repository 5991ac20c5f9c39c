// SPDX-License-Identifier: Apache-2.0
#include "lidar/sensor_clock.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsu::lidar {

SensorClock::SensorClock(const SensorClockConfig& config) : config_(config) {
  if (!(config.max_drift >= 0.0) || !std::isfinite(config.max_drift) || !(config.max_slew > 0.0) ||
      !std::isfinite(config.max_slew) || config.step_threshold <= 0) {
    throw std::invalid_argument("SensorClock: drift must be >= 0, the slew and the step threshold > 0");
  }
}

void SensorClock::observe(TimeNs sensor_end_ns, TimeNs arrival_ns) {
  // Unsigned difference: no overflow for absurd times; clamped to a representable range.
  const TimeNs raw =
      static_cast<TimeNs>(static_cast<std::uint64_t>(arrival_ns) - static_cast<std::uint64_t>(sensor_end_ns));
  last_raw_ = raw;
  const TimeNs sensor_elapsed = sensor_end_ns > last_sensor_ ? sensor_end_ns - last_sensor_ : 0;
  last_sensor_ = sensor_end_ns;
  if (!known_) {
    known_ = true;
    estimate_ = raw;
    stamping_ = raw;
    last_arrival_ = arrival_ns;
    return;
  }
  const TimeNs elapsed = arrival_ns > last_arrival_ ? arrival_ns - last_arrival_ : 0;
  last_arrival_ = arrival_ns;
  // Far off either way: a new clock (raw - estimate computed without overflow for sane clocks).
  const double apart = static_cast<double>(raw) - static_cast<double>(estimate_);
  if (std::abs(apart) > static_cast<double>(config_.step_threshold)) {
    estimate_ = raw;
    stamping_ = raw;
    ++steps_;
    return;
  }
  const auto creep = static_cast<TimeNs>(static_cast<double>(elapsed) * config_.max_drift);
  estimate_ = raw < estimate_ ? raw : std::min(raw, estimate_ + creep);
  // The stamps follow without a jump (file comment).
  const auto slew = static_cast<TimeNs>(
      static_cast<double>(std::min(sensor_elapsed, config_.step_threshold)) * config_.max_slew);
  stamping_ += std::clamp(estimate_ - stamping_, -slew, slew);
}

}  // namespace rsu::lidar
