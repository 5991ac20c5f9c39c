#include "lidar/sensor_clock.h"

#include <cmath>
#include <stdexcept>

namespace rsu {

SensorClock::SensorClock(const SensorClockConfig& config) : config_(config) {
  if (!(config.max_drift >= 0.0) || !std::isfinite(config.max_drift) || config.step_threshold <= 0) {
    throw std::invalid_argument("SensorClock: drift must be >= 0 and the step threshold > 0");
  }
}

void SensorClock::observe(TimeNs sensor_end_ns, TimeNs arrival_ns) {
  // Unsigned difference: no overflow for absurd times; clamped to a representable range.
  const TimeNs raw =
      static_cast<TimeNs>(static_cast<std::uint64_t>(arrival_ns) - static_cast<std::uint64_t>(sensor_end_ns));
  last_raw_ = raw;
  if (!known_) {
    known_ = true;
    estimate_ = raw;
    last_arrival_ = arrival_ns;
    return;
  }
  const TimeNs elapsed = arrival_ns > last_arrival_ ? arrival_ns - last_arrival_ : 0;
  last_arrival_ = arrival_ns;
  // Far off either way: a new clock (raw - estimate computed without overflow for sane clocks).
  const double apart = static_cast<double>(raw) - static_cast<double>(estimate_);
  if (std::abs(apart) > static_cast<double>(config_.step_threshold)) {
    estimate_ = raw;
    ++steps_;
    return;
  }
  const auto creep = static_cast<TimeNs>(static_cast<double>(elapsed) * config_.max_drift);
  estimate_ = raw < estimate_ ? raw : std::min(raw, estimate_ + creep);
}

}  // namespace rsu
