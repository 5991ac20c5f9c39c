// SPDX-License-Identifier: Apache-2.0
// Velodyne packets into points (see velodyne_decoder.h).
#include "lidar/velodyne_decoder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "common/angles.h"

namespace rsu::lidar {
namespace {

constexpr std::array<DecodeResult, 7> kRefusals = {DecodeResult::wrong_size,
                                                   DecodeResult::unknown_product,
                                                   DecodeResult::unsupported_return_mode,
                                                   DecodeResult::bad_block_flag,
                                                   DecodeResult::azimuth_out_of_range,
                                                   DecodeResult::timestamp_out_of_range,
                                                   DecodeResult::dual_pair_mismatch};
constexpr TimeNs kHourNs = 3600 * kNsPerSecond;
// A $GPRMC is used for the hour while the caller's clock says it came less than this long ago.
constexpr TimeNs kGpsHourValidity = 10 * 60 * kNsPerSecond;
// A GPS time and the packet's own timestamp within this of each other (modulo the hour): the sensor's
// clock follows the GPS (its pulse per second or NMEA time).
constexpr TimeNs kGpsAgreement = 2 * kNsPerSecond;
// Packets measuring a rate outside what the sensors run (300-1200 rpm, with room) are not believed.
constexpr double kSlowestRpm = 250.0;
constexpr double kFastestRpm = 1300.0;
constexpr double kRateSmoothing = 1.0 / 32.0;

double rpm_to_degrees_per_us(double rpm) {
  return rpm * 360.0 / 60.0 * 1e-6;
}

// LidarPoint stores the azimuth as float; a double just below 2 pi can round up to float(2 pi),
// outside [0, 2 pi). That direction is azimuth 0.
float to_float_azimuth(double azimuth_rad) {
  const auto a = static_cast<float>(azimuth_rad);
  return a >= static_cast<float>(2.0 * std::numbers::pi) ? 0.0F : a;
}

std::string hex_byte(std::uint8_t b) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", static_cast<unsigned>(b));
  return text;
}

std::string format_utc(TimeNs utc) {
  const std::int64_t seconds = utc / kNsPerSecond;
  const std::int64_t days = seconds / 86400;
  const std::int64_t in_day = seconds % 86400;
  // civil_from_days (H. Hinnant)
  const std::int64_t z = days + 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  const std::int64_t y = static_cast<std::int64_t>(yoe) + era * 400 + (m <= 2 ? 1 : 0);
  char text[40];
  std::snprintf(text, sizeof text, "%04lld-%02u-%02u %02lld:%02lld:%02lld UTC", static_cast<long long>(y), m,
                d, static_cast<long long>(in_day / 3600), static_cast<long long>(in_day / 60 % 60),
                static_cast<long long>(in_day % 60));
  return text;
}

}  // namespace

std::uint64_t VelodyneStats::rejected() const {
  std::uint64_t n = 0;
  for (const DecodeResult r : kRefusals) {
    n += refused_count(r);
  }
  return n;
}

VelodyneDecoder::VelodyneDecoder(const SensorModel& model, ReturnSelection returns,
                                 double rotation_start_azimuth_deg)
    : model_(model),
      returns_(returns),
      rotation_start_rad_(wrap_angle_positive(deg_to_rad(rotation_start_azimuth_deg))),
      degrees_per_us_(nominal_degrees_per_us(model)) {
  if (const std::string error = sensor_model_error(model_); !error.empty()) {
    throw std::invalid_argument(error);
  }
  if (!model_.has_packet_format()) {
    throw std::invalid_argument("sensor model '" + model_.name + "' has no Velodyne packet format");
  }
  if (!std::isfinite(rotation_start_azimuth_deg)) {
    throw std::invalid_argument("the rotation start azimuth must be finite");
  }
  for (const double elevation_deg : model_.elevation_deg) {
    const double w = elevation_deg * std::numbers::pi / 180.0;
    cos_elevation_.push_back(std::cos(w));
    sin_elevation_.push_back(std::sin(w));
  }
  update_geometry();
}

PacketOutcome VelodyneDecoder::refuse(DecodeResult result) {
  last_result_ = result;
  ++stats_.refused[static_cast<std::size_t>(result)];
  return PacketOutcome{PacketKind::refused, to_string(result), 0, 0};
}

std::optional<TimeNs> VelodyneDecoder::gps_reference(TimeNs reference_ns) const {
  if (gps_utc_ && reference_ns - gps_reference_ns_ < kGpsHourValidity &&
      gps_reference_ns_ - reference_ns < kGpsHourValidity) {
    return *gps_utc_ + (reference_ns - gps_reference_ns_);
  }
  return std::nullopt;
}

PacketOutcome VelodyneDecoder::on_position_packet(const PositionPacket& packet, TimeNs reference_ns) {
  ++stats_.position;
  last_result_ = DecodeResult::accepted;
  if (const auto utc = nmea_rmc_utc(packet.nmea)) {
    // The GPS time is the last whole second; the timestamp is this packet's. They agree (within
    // seconds, modulo the hour) only when the sensor's clock follows the GPS.
    const TimeNs stamp = static_cast<TimeNs>(packet.timestamp_us) * kNsPerUs;
    const TimeNs in_hour = ((*utc % kHourNs) + kHourNs) % kHourNs;
    const TimeNs apart =
        std::abs(std::remainder(static_cast<double>(stamp - in_hour), static_cast<double>(kHourNs)));
    if (apart <= kGpsAgreement) {
      gps_utc_ = resolve_hour(stamp, *utc);
      gps_reference_ns_ = reference_ns;
      if (!gps_noticed_) {
        gps_noticed_ = true;
        notices_.push_back("position packets carry GPS time (" + std::string(packet.nmea.substr(0, 6)) + " " +
                           format_utc(*utc) +
                           ") that the sensor's clock follows: the data packets' hour is taken from it");
      }
    }
  }
  return PacketOutcome{PacketKind::auxiliary, "position", 0, 0};
}

void VelodyneDecoder::note_product(std::uint8_t product) {
  ++stats_.product_overridden;
  if (product_noticed_) {
    return;
  }
  product_noticed_ = true;
  notices_.push_back("the packets' factory byte says " + std::string(product_name(product)) + " (" +
                     hex_byte(product) + ") but lidar.model is " + model_.name + " (" +
                     hex_byte(model_.product_id) + "): decoding them as " + model_.name +
                     ", as configured (early VLP-16 firmware reports the HDL-32E's 0x21)");
}

void VelodyneDecoder::note_field_of_view() {
  ++stats_.field_of_view_gaps;
  if (field_of_view_noticed_) {
    return;
  }
  field_of_view_noticed_ = true;
  notices_.push_back(
      "the sensor runs with a limited field of view: nothing is interpolated across the gap, and the "
      "firings after it are timed by the measured rotation rate");
}

void VelodyneDecoder::measure_rate(const PacketTiming& timing) {
  if (!(timing.regular_time_us > 0.0)) {
    return;
  }
  const double rate = timing.regular_turn_deg / timing.regular_time_us;
  if (rate < rpm_to_degrees_per_us(kSlowestRpm) || rate > rpm_to_degrees_per_us(kFastestRpm)) {
    return;  // a stopped or garbled encoder; the sensors do not spin like this
  }
  degrees_per_us_ = rate_measured_ ? degrees_per_us_ + kRateSmoothing * (rate - degrees_per_us_) : rate;
  rate_measured_ = true;
}

LidarPoint VelodyneDecoder::make_point(const Firing& f, std::uint16_t raw, std::uint8_t reflectivity,
                                       std::uint8_t echo) const {
  const double range = raw * model_.distance_unit_m;
  const double horizontal = range * cos_elevation_[f.laser];
  // Sensor frame x forward, y left, z up; Velodyne azimuth is clockwise (sensor_model.h).
  LidarPoint p;
  p.x = static_cast<float>(horizontal * std::cos(f.azimuth_rad));
  p.y = static_cast<float>(-horizontal * std::sin(f.azimuth_rad));
  p.z = static_cast<float>(range * sin_elevation_[f.laser]);
  p.intensity = reflectivity;
  p.ring = f.laser;
  p.echo = echo;
  p.azimuth_rad = to_float_azimuth(f.azimuth_rad);
  p.time_ns = f.time_ns;
  return p;
}

void VelodyneDecoder::append_points(std::vector<LidarPoint>& out) {
  const PacketReturns& r = returns_scratch_;
  const std::size_t before = out.size();
  if (!r.blocks.dual_return) {
    const std::uint8_t echo = r.return_mode == kReturnLast ? kLastReturn : kStrongestReturn;
    for (const Firing& f : firings_) {
      const auto b = static_cast<std::size_t>(f.block);
      const auto c = static_cast<std::size_t>(f.channel);
      const std::uint16_t raw = r.distance_raw[b][c];
      if (raw == 0) {
        ++stats_.no_return;
        continue;
      }
      out.push_back(make_point(f, raw, r.reflectivity[b][c], echo));
    }
    stats_.points += out.size() - before;
    return;
  }
  // Dual: firings_ lists block 2k's firings, then block 2k + 1's (the same firings, the other echo).
  const std::size_t per_block = firings_.size() / kBlocksPerPacket;
  for (std::size_t b = 0; b < kBlocksPerPacket; b += 2) {
    for (std::size_t i = 0; i < per_block; ++i) {
      const Firing& f = firings_[b * per_block + i];
      const auto c = static_cast<std::size_t>(f.channel);
      const std::uint16_t last = r.distance_raw[b][c];
      const std::uint16_t other = r.distance_raw[b + 1][c];
      const std::uint8_t last_refl = r.reflectivity[b][c];
      const std::uint8_t other_refl = r.reflectivity[b + 1][c];
      if (last == 0 && other == 0) {
        ++stats_.no_return;
        continue;
      }
      if (last == other || other == 0 || last == 0) {
        // One echo (reported in both blocks, or only in one): the strongest and the last.
        const bool in_last = last != 0;
        out.push_back(make_point(f, in_last ? last : other, in_last ? last_refl : other_refl,
                                 kStrongestReturn | kLastReturn));
        continue;
      }
      // Two echoes. The other block holds the strongest, or the second strongest when the last echo
      // is itself the strongest: its reflectivity tells which (a tie: the sensor's strongest slot).
      const bool other_is_strongest = other_refl >= last_refl;
      const std::uint8_t last_echo = other_is_strongest ? kLastReturn : (kLastReturn | kStrongestReturn);
      const std::uint8_t other_echo = other_is_strongest ? kStrongestReturn : 0;
      const bool keep_last = returns_ != ReturnSelection::strongest || !other_is_strongest;
      const bool keep_other =
          returns_ == ReturnSelection::both || (returns_ == ReturnSelection::strongest && other_is_strongest);
      if (keep_last) {
        out.push_back(make_point(f, last, last_refl, last_echo));
      }
      if (keep_other) {
        out.push_back(make_point(firings_[(b + 1) * per_block + i], other, other_refl, other_echo));
      }
      stats_.echoes_dropped += (keep_last ? 0 : 1) + (keep_other ? 0 : 1);
    }
  }
  stats_.points += out.size() - before;
}

PacketOutcome VelodyneDecoder::decode(std::span<const std::uint8_t> payload, TimeNs reference_ns,
                                      std::vector<LidarPoint>& out) {
  if (payload.size() == kPositionPacketBytes) {
    if (const auto position = parse_position_packet(payload)) {
      return on_position_packet(*position, reference_ns);
    }
    return refuse(DecodeResult::timestamp_out_of_range);
  }
  const std::optional<TimeNs> gps = gps_reference(reference_ns);
  const DecodeResult result = parse_packet(model_, payload, gps.value_or(reference_ns), returns_scratch_);
  if (result != DecodeResult::accepted) {
    return refuse(result);
  }
  last_result_ = result;
  ++stats_.accepted;
  stats_.gps_hours += gps ? 1 : 0;
  if (returns_scratch_.product_id != model_.product_id) {
    note_product(returns_scratch_.product_id);
  }
  const PacketTiming timing = packet_timing(model_, returns_scratch_.blocks, degrees_per_us_);
  if (timing.field_of_view_gap) {
    note_field_of_view();
  }
  const double rate_before = degrees_per_us_;
  const bool dual_before = last_dual_;
  measure_rate(timing);
  last_dual_ = returns_scratch_.blocks.dual_return;
  if (degrees_per_us_ != rate_before || last_dual_ != dual_before) {
    update_geometry();
  }
  beam_firings(model_, returns_scratch_.blocks, timing, firings_);
  append_points(out);
  return PacketOutcome{PacketKind::data, "accepted", returns_scratch_.blocks.first_firing_ns, timing.end_ns};
}

void VelodyneDecoder::update_geometry() {
  SweepGeometry& g = geometry_;
  g.rotation_hz = degrees_per_us_ * 1e6 / 360.0;
  if (g.ring_azimuth_offset_rad.empty()) {
    for (const double deg : model_.azimuth_offset_deg) {
      g.ring_azimuth_offset_rad.push_back(deg_to_rad(deg));
    }
  }
  // A laser interpolated later into its block than it fires leads the rotor at its firing.
  double lead_us = 0.0;
  for (std::size_t i = 0; i < model_.laser_count(); ++i) {
    lead_us = std::max(lead_us, model_.azimuth_interpolation_us[i] - model_.firing_offset_us[i]);
  }
  g.azimuth_lead_rad = deg_to_rad(lead_us * degrees_per_us_);
  g.rotation_start_azimuth_rad = rotation_start_rad_;
  const int groups = last_dual_ ? kBlocksPerPacket / 2 : kBlocksPerPacket;
  g.packet_period_ns = std::llround(groups * block_duration_us(model_) * 1e3);
}

std::vector<std::pair<std::string, std::uint64_t>> VelodyneDecoder::counters() const {
  std::vector<std::pair<std::string, std::uint64_t>> out;
  out.emplace_back("accepted", stats_.accepted);
  out.emplace_back("position", stats_.position);
  for (const DecodeResult r : kRefusals) {
    out.emplace_back(std::string(to_string(r)), stats_.refused_count(r));
  }
  out.emplace_back("note.product_overridden", stats_.product_overridden);
  out.emplace_back("note.points", stats_.points);
  out.emplace_back("note.no_return", stats_.no_return);
  out.emplace_back("note.echoes_dropped", stats_.echoes_dropped);
  out.emplace_back("note.field_of_view_gaps", stats_.field_of_view_gaps);
  out.emplace_back("note.gps_hours", stats_.gps_hours);
  return out;
}

std::vector<std::string> VelodyneDecoder::take_notices() {
  std::vector<std::string> out;
  out.swap(notices_);
  return out;
}

}  // namespace rsu::lidar
