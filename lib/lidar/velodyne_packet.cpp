// Velodyne data packet codec (see velodyne_packet.h; byte layout from DESIGN.md §2 and the VLP-16 /
// VLP-32C user manuals, "Data Packet Structure").
#include "lidar/velodyne_packet.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rsu {
namespace {

constexpr std::uint8_t kBlockFlag0 = 0xFF;
constexpr std::uint8_t kBlockFlag1 = 0xEE;
constexpr std::uint16_t kAzimuthLimitCdeg = 36000;
constexpr TimeNs kHourNs = 3600 * kNsPerSecond;
constexpr std::uint32_t kHourUs = 3'600'000'000U;

// Product ids from the Velodyne manuals' "Factory Bytes" table: HDL-32E, VLP-16 / Puck LITE,
// Puck Hi-Res, VLP-32C, Velarray, VLS-128.
constexpr std::array<std::uint8_t, 6> kKnownProducts = {0x21, 0x22, 0x24, 0x28, 0x31, 0x63};

std::uint16_t read_u16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8));
}

std::uint32_t read_u32(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint32_t>(b[at]) | (static_cast<std::uint32_t>(b[at + 1]) << 8) |
         (static_cast<std::uint32_t>(b[at + 2]) << 16) | (static_cast<std::uint32_t>(b[at + 3]) << 24);
}

void write_u16(std::span<std::uint8_t> b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<std::uint8_t>(v & 0xFF);
  b[at + 1] = static_cast<std::uint8_t>(v >> 8);
}

void write_u32(std::span<std::uint8_t> b, std::size_t at, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) {
    b[at + i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
  }
}

std::size_t block_offset(std::size_t block) {
  return block * kBlockBytes;
}
std::size_t channel_offset(std::size_t block, std::size_t channel) {
  return block * kBlockBytes + 4 + 3 * channel;
}

TimeNs floor_div(TimeNs a, TimeNs b) {
  const TimeNs q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

// The time of `ns_past_hour` in the hour that puts it nearest `reference_ns`.
TimeNs resolve_hour(TimeNs ns_past_hour, TimeNs reference_ns) {
  // Keep clear of int64 overflow for absurd references (2^63 ns is ~292 years).
  constexpr TimeNs kLimit = std::numeric_limits<TimeNs>::max() - 3 * kHourNs;
  reference_ns = std::clamp(reference_ns, -kLimit, kLimit);
  TimeNs t = floor_div(reference_ns, kHourNs) * kHourNs + ns_past_hour;
  if (t - reference_ns > kHourNs / 2) {
    t -= kHourNs;
  } else if (reference_ns - t > kHourNs / 2) {
    t += kHourNs;
  }
  return t;
}

// LidarPoint stores the azimuth as float; a double just below 2 pi can round up to float(2 pi),
// outside [0, 2 pi). That direction is azimuth 0.
float to_float_azimuth(double azimuth_rad) {
  const auto a = static_cast<float>(azimuth_rad);
  return a >= static_cast<float>(2.0 * std::numbers::pi) ? 0.0F : a;
}

void require_packet_format(const SensorModel& model) {
  if (const std::string error = sensor_model_error(model); !error.empty()) {
    throw std::invalid_argument(error);
  }
  if (!model.has_packet_format()) {
    throw std::invalid_argument("sensor model '" + model.name + "' has no Velodyne packet format");
  }
}

}  // namespace

std::uint16_t quantize_distance(const SensorModel& model, double range_m) {
  if (!(range_m >= model.min_range_m && range_m <= model.max_range_m)) {
    return 0;  // also NaN
  }
  const double units = std::round(range_m / model.distance_unit_m);
  // A positive range never quantises to 0, which would read as "no return".
  return static_cast<std::uint16_t>(std::clamp(units, 1.0, 65535.0));
}

void encode_packet(const SensorModel& model, const PacketReturns& returns,
                   std::span<std::uint8_t, kPacketBytes> out) {
  require_packet_format(model);
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    out[block_offset(b)] = kBlockFlag0;
    out[block_offset(b) + 1] = kBlockFlag1;
    write_u16(out, block_offset(b) + 2, returns.blocks.azimuth_cdeg[b]);
    for (std::size_t c = 0; c < kChannelsPerBlock; ++c) {
      write_u16(out, channel_offset(b, c), returns.distance_raw[b][c]);
      out[channel_offset(b, c) + 2] = returns.reflectivity[b][c];
    }
  }
  const TimeNs ns_past_hour =
      returns.blocks.first_firing_ns - floor_div(returns.blocks.first_firing_ns, kHourNs) * kHourNs;
  write_u32(out, kTimestampOffset, static_cast<std::uint32_t>(ns_past_hour / kNsPerUs));
  out[kReturnModeOffset] = returns.return_mode;
  out[kProductIdOffset] = model.product_id;
}

std::string_view to_string(DecodeResult result) {
  switch (result) {
    case DecodeResult::accepted:
      return "accepted";
    case DecodeResult::wrong_size:
      return "wrong_size";
    case DecodeResult::unknown_product:
      return "unknown_product";
    case DecodeResult::product_mismatch:
      return "product_mismatch";
    case DecodeResult::unsupported_return_mode:
      return "unsupported_return_mode";
    case DecodeResult::bad_block_flag:
      return "bad_block_flag";
    case DecodeResult::azimuth_out_of_range:
      return "azimuth_out_of_range";
    case DecodeResult::timestamp_out_of_range:
      return "timestamp_out_of_range";
  }
  return "unknown";
}

std::uint64_t DecodeStats::packets() const {
  return accepted + wrong_size + unknown_product + product_mismatch + unsupported_return_mode +
         bad_block_flag + azimuth_out_of_range + timestamp_out_of_range;
}

DecodeResult parse_packet(const SensorModel& model, std::span<const std::uint8_t> payload,
                          TimeNs reference_ns, PacketReturns& out) {
  if (payload.size() != kPacketBytes) {
    return DecodeResult::wrong_size;
  }
  const std::uint8_t product = payload[kProductIdOffset];
  if (std::find(kKnownProducts.begin(), kKnownProducts.end(), product) == kKnownProducts.end()) {
    return DecodeResult::unknown_product;
  }
  if (product != model.product_id) {
    return DecodeResult::product_mismatch;
  }
  const std::uint8_t mode = payload[kReturnModeOffset];
  if (mode != kReturnStrongest && mode != kReturnLast) {
    return DecodeResult::unsupported_return_mode;
  }
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    if (payload[block_offset(b)] != kBlockFlag0 || payload[block_offset(b) + 1] != kBlockFlag1) {
      return DecodeResult::bad_block_flag;
    }
  }
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    if (read_u16(payload, block_offset(b) + 2) >= kAzimuthLimitCdeg) {
      return DecodeResult::azimuth_out_of_range;
    }
  }
  const std::uint32_t timestamp_us = read_u32(payload, kTimestampOffset);
  if (timestamp_us >= kHourUs) {
    return DecodeResult::timestamp_out_of_range;
  }

  // Valid: only now touch `out`.
  out.blocks.first_firing_ns = resolve_hour(static_cast<TimeNs>(timestamp_us) * kNsPerUs, reference_ns);
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    out.blocks.azimuth_cdeg[b] = read_u16(payload, block_offset(b) + 2);
    for (std::size_t c = 0; c < kChannelsPerBlock; ++c) {
      out.distance_raw[b][c] = read_u16(payload, channel_offset(b, c));
      out.reflectivity[b][c] = payload[channel_offset(b, c) + 2];
    }
  }
  out.return_mode = mode;
  return DecodeResult::accepted;
}

PacketDecoder::PacketDecoder(const SensorModel& model) : model_(model) {
  require_packet_format(model_);
  for (const double elevation_deg : model_.elevation_deg) {
    const double w = elevation_deg * std::numbers::pi / 180.0;
    cos_elevation_.push_back(std::cos(w));
    sin_elevation_.push_back(std::sin(w));
  }
}

void PacketDecoder::count(DecodeResult result) {
  switch (result) {
    case DecodeResult::accepted:
      ++stats_.accepted;
      break;
    case DecodeResult::wrong_size:
      ++stats_.wrong_size;
      break;
    case DecodeResult::unknown_product:
      ++stats_.unknown_product;
      break;
    case DecodeResult::product_mismatch:
      ++stats_.product_mismatch;
      break;
    case DecodeResult::unsupported_return_mode:
      ++stats_.unsupported_return_mode;
      break;
    case DecodeResult::bad_block_flag:
      ++stats_.bad_block_flag;
      break;
    case DecodeResult::azimuth_out_of_range:
      ++stats_.azimuth_out_of_range;
      break;
    case DecodeResult::timestamp_out_of_range:
      ++stats_.timestamp_out_of_range;
      break;
  }
}

DecodeResult PacketDecoder::decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                                   std::vector<LidarPoint>& out) {
  const DecodeResult result = parse_packet(model_, payload, reference_ns, returns_);
  count(result);
  if (result != DecodeResult::accepted) {
    return result;
  }
  beam_firings(model_, returns_.blocks, firings_);
  for (const Firing& f : firings_) {
    const auto b = static_cast<std::size_t>(f.block);
    const auto c = static_cast<std::size_t>(f.channel);
    const std::uint16_t raw = returns_.distance_raw[b][c];
    if (raw == 0) {
      ++stats_.no_return;
      continue;
    }
    const double range = raw * model_.distance_unit_m;
    const double horizontal = range * cos_elevation_[f.laser];
    // Sensor frame x forward, y left, z up; Velodyne azimuth is clockwise (sensor_model.h).
    LidarPoint p;
    p.x = static_cast<float>(horizontal * std::cos(f.azimuth_rad));
    p.y = static_cast<float>(-horizontal * std::sin(f.azimuth_rad));
    p.z = static_cast<float>(range * sin_elevation_[f.laser]);
    p.intensity = returns_.reflectivity[b][c];
    p.ring = f.laser;
    p.azimuth_rad = to_float_azimuth(f.azimuth_rad);
    p.time_ns = f.time_ns;
    out.push_back(p);
    ++stats_.points_decoded;
  }
  return result;
}

}  // namespace rsu
