// SPDX-License-Identifier: Apache-2.0
// Velodyne data packet codec (see velodyne_packet.h; byte layout from docs/design.md §2 and the VLP-16 /
// VLP-32C user manuals, "Data Packet Structure").
#include "lidar/velodyne_packet.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rsu::lidar {
namespace {

constexpr std::uint8_t kBlockFlag0 = 0xFF;
constexpr std::uint8_t kBlockFlag1 = 0xEE;
constexpr std::uint16_t kAzimuthLimitCdeg = 36000;
constexpr TimeNs kHourNs = 3600 * kNsPerSecond;
constexpr std::uint32_t kHourUs = 3'600'000'000U;

// Product ids from the Velodyne manuals' "Factory Bytes" table.
struct Product {
  std::uint8_t id;
  std::string_view name;
};
constexpr std::array<Product, 6> kKnownProducts = {{{0x21, "HDL-32E"},
                                                    {0x22, "VLP-16"},
                                                    {0x24, "Puck Hi-Res"},
                                                    {0x28, "VLP-32C"},
                                                    {0x31, "Velarray"},
                                                    {0x63, "VLS-128"}}};
constexpr std::size_t kPositionTimestampOffset = 198;
constexpr std::size_t kPositionNmeaOffset = 206;

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
  const TimeNs stamp_ns =
      returns.blocks.first_firing_ns - std::llround(model.first_firing_after_timestamp_us * 1e3);
  const TimeNs ns_past_hour = stamp_ns - floor_div(stamp_ns, kHourNs) * kHourNs;
  write_u32(out, kTimestampOffset, static_cast<std::uint32_t>(ns_past_hour / kNsPerUs));
  out[kReturnModeOffset] = returns.blocks.dual_return ? kReturnDual : returns.return_mode;
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
    case DecodeResult::unsupported_return_mode:
      return "unsupported_return_mode";
    case DecodeResult::bad_block_flag:
      return "bad_block_flag";
    case DecodeResult::azimuth_out_of_range:
      return "azimuth_out_of_range";
    case DecodeResult::timestamp_out_of_range:
      return "timestamp_out_of_range";
    case DecodeResult::dual_pair_mismatch:
      return "dual_pair_mismatch";
  }
  return "unknown";
}

std::string_view product_name(std::uint8_t product_id) {
  for (const Product& p : kKnownProducts) {
    if (p.id == product_id) {
      return p.name;
    }
  }
  return {};
}

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

DecodeResult parse_packet(const SensorModel& model, std::span<const std::uint8_t> payload,
                          TimeNs reference_ns, PacketReturns& out) {
  if (payload.size() != kPacketBytes) {
    return DecodeResult::wrong_size;
  }
  const std::uint8_t product = payload[kProductIdOffset];
  if (product_name(product).empty()) {
    return DecodeResult::unknown_product;
  }
  const std::uint8_t mode = payload[kReturnModeOffset];
  if (mode != kReturnStrongest && mode != kReturnLast && mode != kReturnDual) {
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
  if (mode == kReturnDual) {
    for (std::size_t b = 0; b < kBlocksPerPacket; b += 2) {
      if (read_u16(payload, block_offset(b) + 2) != read_u16(payload, block_offset(b + 1) + 2)) {
        return DecodeResult::dual_pair_mismatch;
      }
    }
  }

  // Valid: only now touch `out`.
  out.blocks.first_firing_ns = resolve_hour(static_cast<TimeNs>(timestamp_us) * kNsPerUs, reference_ns) +
                               std::llround(model.first_firing_after_timestamp_us * 1e3);
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    out.blocks.azimuth_cdeg[b] = read_u16(payload, block_offset(b) + 2);
    for (std::size_t c = 0; c < kChannelsPerBlock; ++c) {
      out.distance_raw[b][c] = read_u16(payload, channel_offset(b, c));
      out.reflectivity[b][c] = payload[channel_offset(b, c) + 2];
    }
  }
  out.blocks.dual_return = mode == kReturnDual;
  out.return_mode = mode;
  out.product_id = product;
  return DecodeResult::accepted;
}

std::optional<PositionPacket> parse_position_packet(std::span<const std::uint8_t> payload) {
  if (payload.size() != kPositionPacketBytes) {
    return std::nullopt;
  }
  PositionPacket p;
  p.timestamp_us = read_u32(payload, kPositionTimestampOffset);
  if (p.timestamp_us >= kHourUs) {
    return std::nullopt;
  }
  const auto text = payload.subspan(kPositionNmeaOffset);
  std::size_t n = 0;
  while (n < text.size() && text[n] != 0 && text[n] != '\r' && text[n] != '\n') {
    ++n;
  }
  // The bytes are the packet's own: a view of them stays valid as long as the caller's payload does.
  p.nmea = std::string_view(reinterpret_cast<const char*>(text.data()), n);
  return p;
}

namespace {

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

// The digits text[at, at + n) as a number; nullopt if any is not a digit.
std::optional<unsigned> digits(std::string_view text, std::size_t at, std::size_t n) {
  if (at + n > text.size()) {
    return std::nullopt;
  }
  unsigned v = 0;
  for (std::size_t i = at; i < at + n; ++i) {
    if (text[i] < '0' || text[i] > '9') {
      return std::nullopt;
    }
    v = v * 10 + static_cast<unsigned>(text[i] - '0');
  }
  return v;
}

}  // namespace

std::optional<TimeNs> nmea_rmc_utc(std::string_view s) {
  // $ttRMC,hhmmss[.sss],A,lat,N,lon,E,speed,course,ddmmyy,...*CS
  if (s.size() < 7 || s[0] != '$' || s.substr(3, 4) != "RMC,") {
    return std::nullopt;
  }
  const std::size_t star = s.rfind('*');
  if (star == std::string_view::npos || star + 3 > s.size()) {
    return std::nullopt;
  }
  unsigned sum = 0;
  for (std::size_t i = 1; i < star; ++i) {
    sum ^= static_cast<unsigned char>(s[i]);
  }
  unsigned stated = 0;
  for (std::size_t i = star + 1; i < star + 3; ++i) {
    const char c = s[i];
    const int v = c >= '0' && c <= '9' ? c - '0' : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
    if (v < 0) {
      return std::nullopt;
    }
    stated = stated * 16 + static_cast<unsigned>(v);
  }
  if (stated != sum) {
    return std::nullopt;
  }
  // Fields after the sentence name: 1 time, 2 status, ..., 9 date.
  std::array<std::string_view, 10> field{};
  std::size_t begin = 7;
  for (std::size_t f = 1; f < field.size(); ++f) {
    const std::size_t comma = s.find(',', begin);
    const std::size_t end = comma == std::string_view::npos ? star : std::min(comma, star);
    field[f] = s.substr(begin, end - begin);
    if (end == star && f + 1 < field.size()) {
      return std::nullopt;  // fewer fields than a date needs
    }
    begin = end + 1;
  }
  const std::string_view time = field[1];
  const std::string_view date = field[9];
  if (field[2] != "A" || time.size() < 6 || date.size() != 6) {
    return std::nullopt;
  }
  const auto hh = digits(time, 0, 2);
  const auto mm = digits(time, 2, 2);
  const auto ss = digits(time, 4, 2);
  const auto day = digits(date, 0, 2);
  const auto month = digits(date, 2, 2);
  const auto yy = digits(date, 4, 2);
  if (!hh || !mm || !ss || !day || !month || !yy || *hh > 23 || *mm > 59 || *ss > 60 || *day < 1 ||
      *day > 31 || *month < 1 || *month > 12) {
    return std::nullopt;
  }
  // Two-digit years: 1980-2079 (GPS time begins in 1980).
  const std::int64_t year = *yy >= 80 ? 1900 + *yy : 2000 + *yy;
  const std::int64_t days = days_from_civil(year, *month, *day);
  return (days * 86400 + std::int64_t{*hh} * 3600 + std::int64_t{*mm} * 60 + *ss) * kNsPerSecond;
}

}  // namespace rsu::lidar
