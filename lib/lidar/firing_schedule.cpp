// Firing times and beam angles of a spinning Velodyne-like sensor (see firing_schedule.h).
#include "lidar/firing_schedule.h"

#include <cmath>
#include <stdexcept>

#include "common/angles.h"

namespace rsu {
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
  blocks.first_firing_ns = round_to_multiple(t0_ + k * packet_period_ns(), kNsPerUs);
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

std::vector<Firing> beam_firings(const SensorModel& model, const PacketBlocks& blocks) {
  std::vector<Firing> out;
  beam_firings(model, blocks, out);
  return out;
}

void beam_firings(const SensorModel& model, const PacketBlocks& blocks, std::vector<Firing>& out) {
  require_valid(model);
  out.clear();
  const int lasers = static_cast<int>(model.laser_count());
  const double block_us = block_duration_us(model);
  out.reserve(static_cast<std::size_t>(kBlocksPerPacket * model.sequences_per_block * lasers));

  // Azimuth advance from block b to b + 1 in 0.01 deg, modulo a turn (the encoder wraps at 36000).
  std::array<int, kBlocksPerPacket> diff_cdeg{};
  for (int b = 0; b + 1 < kBlocksPerPacket; ++b) {
    const int d = static_cast<int>(blocks.azimuth_cdeg[static_cast<std::size_t>(b + 1)]) -
                  static_cast<int>(blocks.azimuth_cdeg[static_cast<std::size_t>(b)]);
    diff_cdeg[static_cast<std::size_t>(b)] = ((d % kCdegPerTurn) + kCdegPerTurn) % kCdegPerTurn;
  }
  // The last block's successor is in the next packet, which the decoder has not seen: reuse the
  // previous difference (as the Velodyne manuals' precision-azimuth procedure does).
  diff_cdeg[kBlocksPerPacket - 1] = diff_cdeg[kBlocksPerPacket - 2];

  for (int b = 0; b < kBlocksPerPacket; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    const TimeNs block_start_ns = blocks.first_firing_ns + us_to_ns(b * block_us);
    const double block_az_deg = blocks.azimuth_cdeg[bi] / 100.0;
    const double diff_deg = diff_cdeg[bi] / 100.0;
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
        f.time_ns = block_start_ns + us_to_ns(dt_us);
        f.azimuth_rad = wrap_0_2pi(deg_to_rad(az_deg));
        out.push_back(f);
      }
    }
  }
}

}  // namespace rsu
