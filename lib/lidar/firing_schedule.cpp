// SPDX-License-Identifier: Apache-2.0
// Firing times and beam angles of a spinning Velodyne-like sensor (see firing_schedule.h).
#include "lidar/firing_schedule.h"

#include <cmath>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::lidar {
namespace {

constexpr int kCdegPerTurn = 36000;

void require_valid(const SensorModel& model) {
  if (const std::string error = sensor_model_error(model); !error.empty()) {
    throw std::invalid_argument(error);
  }
}

// Nearest multiple of `unit` (> 0), rounding halves away from zero, exact for any int64 input in range.
TimeNs round_to_multiple(TimeNs t, TimeNs unit) {
  TimeNs q = t / unit;
  TimeNs r = t % unit;  // same sign as t
  if (2 * r >= unit) {
    ++q;
  } else if (2 * r <= -unit) {
    --q;
  }
  return q * unit;
}

TimeNs us_to_ns(double us) {
  return static_cast<TimeNs>(std::llround(us * 1e3));
}

// [0, 2 pi): wrap_angle_positive can return exactly 2 pi for a tiny negative input.
double wrap_0_2pi(double a) {
  const double w = wrap_angle_positive(a);
  return w >= 2.0 * kPi ? 0.0 : w;
}

}  // namespace

double block_duration_us(const SensorModel& model) {
  return model.sequences_per_block * model.sequence_period_us;
}

FiringSchedule::FiringSchedule(const SensorModel& model, TimeNs t0, double start_azimuth_deg)
    : model_(model), t0_(t0), start_azimuth_deg_(start_azimuth_deg) {
  require_valid(model_);
  if (!std::isfinite(start_azimuth_deg)) {
    throw std::invalid_argument("FiringSchedule: start azimuth must be finite");
  }
}

TimeNs FiringSchedule::packet_period_ns() const {
  return us_to_ns(kBlocksPerPacket * block_duration_us(model_));
}

std::uint16_t FiringSchedule::encoder_azimuth_cdeg(TimeNs t) const {
  // Whole turns are dropped before scaling to degrees so that precision does not degrade over hours.
  const double turns = model_.rotation_hz() * to_seconds(t - t0_);
  double deg = start_azimuth_deg_ + 360.0 * (turns - std::floor(turns));
  deg = std::fmod(deg, 360.0);
  if (deg < 0.0) {
    deg += 360.0;
  }
  long long cdeg = std::llround(deg * 100.0);
  if (cdeg >= kCdegPerTurn) {
    cdeg -= kCdegPerTurn;  // 359.995 deg rounds to 36000, which is 0
  }
  return static_cast<std::uint16_t>(cdeg);
}

PacketBlocks FiringSchedule::packet(std::int64_t k) const {
  PacketBlocks blocks;
  // The packet's timestamp (its first firing, or its end: SensorModel) on the microsecond grid.
  const TimeNs stamp_offset = us_to_ns(model_.first_firing_after_timestamp_us);
  blocks.first_firing_ns =
      round_to_multiple(t0_ + k * packet_period_ns() - stamp_offset, kNsPerUs) + stamp_offset;
  const double block_us = block_duration_us(model_);
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    blocks.azimuth_cdeg[static_cast<std::size_t>(b)] =
        encoder_azimuth_cdeg(blocks.first_firing_ns + us_to_ns(b * block_us));
  }
  return blocks;
}

std::vector<Firing> FiringSchedule::firings(const PacketBlocks& blocks) const {
  return beam_firings(model_, blocks);
}

double nominal_degrees_per_us(const SensorModel& model) {
  return 360.0 * model.rotation_hz() * 1e-6;
}

PacketTiming packet_timing(const SensorModel& model, const PacketBlocks& blocks, double degrees_per_us) {
  require_valid(model);
  if (!(degrees_per_us > 0.0) || !std::isfinite(degrees_per_us)) {
    throw std::invalid_argument("packet_timing: the rotation rate must be positive");
  }
  const int step = blocks.dual_return ? 2 : 1;
  const int groups = kBlocksPerPacket / step;
  const double block_us = block_duration_us(model);
  // A rotor at the fastest rate any of these sensors runs (1200 rpm) turns this far in one block; a
  // larger step between two groups of one packet is a field-of-view gap.
  const double regular_limit_deg = 1.5 * 360.0 * (1200.0 / 60.0) * block_us * 1e-6;

  std::array<double, kBlocksPerPacket> step_deg{};  // group g -> g + 1 (groups indexed 0..groups-1)
  std::array<bool, kBlocksPerPacket> regular{};
  PacketTiming t;
  for (int g = 0; g + 1 < groups; ++g) {
    const int d = static_cast<int>(blocks.azimuth_cdeg[static_cast<std::size_t>((g + 1) * step)]) -
                  static_cast<int>(blocks.azimuth_cdeg[static_cast<std::size_t>(g * step)]);
    const auto gi = static_cast<std::size_t>(g);
    step_deg[gi] = (((d % kCdegPerTurn) + kCdegPerTurn) % kCdegPerTurn) / 100.0;
    regular[gi] = step_deg[gi] <= regular_limit_deg;
    if (regular[gi]) {
      t.regular_turn_deg += step_deg[gi];
      t.regular_time_us += block_us;
    } else {
      t.field_of_view_gap = true;
    }
  }
  // The difference a group interpolates with: its own step if regular, else the nearest regular one
  // before it, else after it, else the measured rate over one block.
  auto nearest_regular = [&](int g) {
    for (int k = g - 1; k >= 0; --k) {
      if (regular[static_cast<std::size_t>(k)]) {
        return step_deg[static_cast<std::size_t>(k)];
      }
    }
    for (int k = g + 1; k + 1 < groups; ++k) {
      if (regular[static_cast<std::size_t>(k)]) {
        return step_deg[static_cast<std::size_t>(k)];
      }
    }
    return degrees_per_us * block_us;
  };
  TimeNs start = blocks.first_firing_ns;
  for (int g = 0; g < groups; ++g) {
    const auto gi = static_cast<std::size_t>(g);
    const bool own = g + 1 < groups && regular[gi];
    const double diff = own ? step_deg[gi] : nearest_regular(g);
    for (int s = 0; s < step; ++s) {
      const auto bi = static_cast<std::size_t>(g * step + s);
      t.block_start_ns[bi] = start;
      t.diff_deg[bi] = diff;
    }
    if (g + 1 < groups) {
      start += regular[gi] ? us_to_ns(block_us) : us_to_ns(step_deg[gi] / degrees_per_us);
    }
  }
  t.end_ns = t.block_start_ns[kBlocksPerPacket - 1] + us_to_ns(block_us);
  return t;
}

std::vector<Firing> beam_firings(const SensorModel& model, const PacketBlocks& blocks) {
  std::vector<Firing> out;
  beam_firings(model, blocks, packet_timing(model, blocks, nominal_degrees_per_us(model)), out);
  return out;
}

void beam_firings(const SensorModel& model, const PacketBlocks& blocks, const PacketTiming& timing,
                  std::vector<Firing>& out) {
  require_valid(model);
  out.clear();
  const int lasers = static_cast<int>(model.laser_count());
  const double block_us = block_duration_us(model);
  out.reserve(static_cast<std::size_t>(kBlocksPerPacket * model.sequences_per_block * lasers));
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    const double block_az_deg = blocks.azimuth_cdeg[bi] / 100.0;
    const double diff_deg = timing.diff_deg[bi];
    for (int s = 0; s < model.sequences_per_block; ++s) {
      for (int laser = 0; laser < lasers; ++laser) {
        const auto li = static_cast<std::size_t>(laser);
        const double sequence_us = s * model.sequence_period_us;
        const double dt_us = sequence_us + model.firing_offset_us[li];
        const double az_dt_us = sequence_us + model.azimuth_interpolation_us[li];
        const double az_deg = block_az_deg + diff_deg * az_dt_us / block_us + model.azimuth_offset_deg[li];
        Firing f;
        f.block = b;
        f.channel = s * lasers + laser;
        f.laser = static_cast<std::uint16_t>(laser);
        f.time_ns = timing.block_start_ns[bi] + us_to_ns(dt_us);
        f.azimuth_rad = wrap_0_2pi(deg_to_rad(az_deg));
        out.push_back(f);
      }
    }
  }
}

}  // namespace rsu::lidar
