// SPDX-License-Identifier: Apache-2.0
#include "lidar/velodyne_packet.h"

#include "lidar/velodyne_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/angles.h"
#include "packet_stream.h"
#include "published_tables.h"

namespace rsu::lidar {
namespace {

constexpr TimeNs kHour = 3600 * kNsPerSecond;

std::uint16_t le16(const std::array<std::uint8_t, kPacketBytes>& b, std::size_t at) {
  return static_cast<std::uint16_t>(b[at] + 256 * b[at + 1]);
}

double elevation_deg(const SensorModel& m, std::size_t laser) {
  if (m.name == "hdl32e") {
    return test::kHdl32eElevationDeg[laser];
  }
  return m.name == "vlp16" ? test::kVlp16ElevationDeg[laser] : test::kVlp32cElevationDeg[laser];
}

TEST(LidarVelodynePacket, QuantizeDistance) {
  const SensorModel vlp16 = make_vlp16();
  EXPECT_EQ(quantize_distance(vlp16, 10.0), 5000);
  EXPECT_EQ(quantize_distance(vlp16, 10.0011), 5001);  // nearest 2 mm
  EXPECT_EQ(quantize_distance(vlp16, 10.0009), 5000);
  EXPECT_EQ(quantize_distance(vlp16, 100.0), 50000);
  EXPECT_EQ(quantize_distance(vlp16, 100.01), 0);
  EXPECT_EQ(quantize_distance(vlp16, vlp16.min_range_m - 0.01), 0);
  EXPECT_EQ(quantize_distance(vlp16, -3.0), 0);
  EXPECT_EQ(quantize_distance(vlp16, std::nan("")), 0);
  EXPECT_EQ(quantize_distance(vlp16, std::numeric_limits<double>::infinity()), 0);
  EXPECT_EQ(quantize_distance(make_vlp32c(), 150.0), 37500);  // 4 mm units
}

TEST(LidarVelodynePacket, EncodedByteLayout) {
  const SensorModel model = make_vlp32c();
  PacketReturns r;
  r.blocks.first_firing_ns = 7 * kHour + 1'234'567'891;  // 1234567 us (and 891 ns) past the hour
  for (std::size_t b = 0; b < 12; ++b) {
    r.blocks.azimuth_cdeg[b] = static_cast<std::uint16_t>(35990 + b);
    for (std::size_t c = 0; c < 32; ++c) {
      r.distance_raw[b][c] = static_cast<std::uint16_t>(1000 * b + c + 0x100);
      r.reflectivity[b][c] = static_cast<std::uint8_t>(b + c);
    }
  }
  r.return_mode = kReturnLast;
  std::array<std::uint8_t, kPacketBytes> bytes{};
  encode_packet(model, r, bytes);
  for (std::size_t b = 0; b < 12; ++b) {
    EXPECT_EQ(bytes[100 * b], 0xFF);
    EXPECT_EQ(bytes[100 * b + 1], 0xEE);
    EXPECT_EQ(le16(bytes, 100 * b + 2), 35990 + b);
    for (std::size_t c = 0; c < 32; ++c) {
      EXPECT_EQ(le16(bytes, 100 * b + 4 + 3 * c), 1000 * b + c + 0x100);
      EXPECT_EQ(bytes[100 * b + 6 + 3 * c], b + c);
    }
  }
  const std::uint32_t ts = bytes[1200] | (bytes[1201] << 8) | (bytes[1202] << 16) |
                           (static_cast<std::uint32_t>(bytes[1203]) << 24);
  EXPECT_EQ(ts, 1'234'567U);
  EXPECT_EQ(bytes[1204], 0x38);
  EXPECT_EQ(bytes[1205], 0x28);
}

// Encode -> decode reproduces every return: same time and azimuth as the schedule, range within half
// a distance unit of the truth, xyz = range * direction from the published elevation.
void check_round_trip(const SensorModel& model) {
  std::mt19937_64 rng(17);
  const FiringSchedule schedule(model, 1'700'000'000 * kNsPerSecond + 55'555, 250.0);
  VelodyneDecoder decoder(model);
  std::uint64_t expected_points = 0;
  std::uint64_t expected_none = 0;
  for (std::int64_t k = 0; k < 60; ++k) {
    const test::EncodedPacket packet = test::make_packet(schedule, k, rng, 0.2);
    std::vector<LidarPoint> points;
    const TimeNs received = packet.returns.blocks.first_firing_ns + 2 * kNsPerMs;
    ASSERT_EQ(decoder.decode(packet.bytes, received, points).reason, "accepted");
    std::size_t next = 0;
    for (std::size_t i = 0; i < packet.firings.size(); ++i) {
      const Firing& f = packet.firings[i];
      if (packet.true_range_m[i] == 0.0) {
        ++expected_none;
        continue;
      }
      ++expected_points;
      ASSERT_LT(next, points.size());
      const LidarPoint& p = points[next++];
      EXPECT_EQ(p.time_ns, f.time_ns);
      EXPECT_EQ(p.ring, f.laser);
      EXPECT_FLOAT_EQ(p.azimuth_rad, static_cast<float>(f.azimuth_rad));
      EXPECT_EQ(p.intensity, packet.returns.reflectivity[static_cast<std::size_t>(f.block)]
                                                        [static_cast<std::size_t>(f.channel)]);
      const double x = static_cast<double>(p.x), y = static_cast<double>(p.y), z = static_cast<double>(p.z);
      const double range = std::sqrt(x * x + y * y + z * z);
      EXPECT_NEAR(range, packet.true_range_m[i], model.distance_unit_m / 2 + 2e-5 * range);
      // Direction from the test's own table: elevation w, clockwise azimuth a.
      const double w = deg_to_rad(elevation_deg(model, f.laser));
      const double a = f.azimuth_rad;
      EXPECT_NEAR(x, range * std::cos(w) * std::cos(a), 1e-5 * range + 1e-6);
      EXPECT_NEAR(y, -range * std::cos(w) * std::sin(a), 1e-5 * range + 1e-6);
      EXPECT_NEAR(z, range * std::sin(w), 1e-5 * range + 1e-6);
    }
    EXPECT_EQ(next, points.size());
  }
  EXPECT_EQ(decoder.stats().accepted, 60U);
  EXPECT_EQ(decoder.stats().rejected(), 0U);
  EXPECT_EQ(decoder.stats().points, expected_points);
  EXPECT_EQ(decoder.stats().no_return, expected_none);
}

TEST(LidarVelodynePacket, RoundTripVlp16) {
  check_round_trip(make_vlp16());
}
TEST(LidarVelodynePacket, RoundTripVlp32c) {
  check_round_trip(make_vlp32c());
}

TEST(LidarVelodynePacket, RoundTripHdl32e) {
  check_round_trip(make_hdl32e());
}

TEST(LidarVelodynePacket, ParseReproducesRawContent) {
  const SensorModel model = make_vlp16();
  std::mt19937_64 rng(3);
  const FiringSchedule schedule(model, 42 * kNsPerSecond);
  const test::EncodedPacket packet = test::make_packet(schedule, 9, rng, 0.3);
  PacketReturns parsed;
  ASSERT_EQ(parse_packet(model, packet.bytes, packet.returns.blocks.first_firing_ns, parsed),
            DecodeResult::accepted);
  EXPECT_EQ(parsed.blocks.first_firing_ns, packet.returns.blocks.first_firing_ns);
  EXPECT_EQ(parsed.blocks.azimuth_cdeg, packet.returns.blocks.azimuth_cdeg);
  EXPECT_EQ(parsed.distance_raw, packet.returns.distance_raw);
  EXPECT_EQ(parsed.reflectivity, packet.returns.reflectivity);
  EXPECT_EQ(parsed.return_mode, kReturnStrongest);
}

TEST(LidarVelodynePacket, TopOfHourWrap) {
  const SensorModel model = make_vlp32c();
  std::mt19937_64 rng(5);
  // The stream crosses 06:00:00 a few packets in; packet 1 itself straddles the hour.
  const TimeNs hour = 123'456 * kHour;
  const FiringSchedule schedule(model, hour - 900 * kNsPerUs);
  VelodyneDecoder decoder(model);
  for (std::int64_t k = 0; k < 6; ++k) {
    const test::EncodedPacket packet = test::make_packet(schedule, k, rng, 0.0);
    const TimeNs truth = packet.returns.blocks.first_firing_ns;
    // A reference on either side of the hour, near or up to 29 minutes away, resolves the same hour.
    for (const TimeNs delta :
         {TimeNs{0}, 3 * kNsPerMs, -3 * kNsPerMs, 29 * 60 * kNsPerSecond, -29 * 60 * kNsPerSecond}) {
      std::vector<LidarPoint> points;
      ASSERT_TRUE(decoder.decode(packet.bytes, truth + delta, points).is_data());
      ASSERT_EQ(points.size(), packet.firings.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        ASSERT_EQ(points[i].time_ns, packet.firings[i].time_ns) << "packet " << k << " delta " << delta;
      }
    }
    // More than half an hour away, the nearest hour is the wrong one: documented, not hidden.
    std::vector<LidarPoint> points;
    ASSERT_TRUE(decoder.decode(packet.bytes, truth + 31 * 60 * kNsPerSecond, points).is_data());
    EXPECT_EQ(points.front().time_ns, packet.firings.front().time_ns + kHour);
  }
}

TEST(LidarVelodynePacket, RejectsWrongSizes) {
  const SensorModel model = make_vlp16();
  std::mt19937_64 rng(1);
  const test::EncodedPacket packet = test::make_packet(FiringSchedule(model, 0), 0, rng, 0.0);
  VelodyneDecoder decoder(model);
  std::vector<LidarPoint> points(3);  // pre-existing content must survive rejections
  std::vector<std::uint8_t> longer(packet.bytes.begin(), packet.bytes.end());
  longer.push_back(0);
  for (const std::size_t n : {0UL, 1UL, 100UL, 1200UL, 1205UL}) {
    const PacketOutcome outcome = decoder.decode(std::span(packet.bytes).first(n), 0, points);
    EXPECT_EQ(outcome.kind, PacketKind::refused) << n;
    EXPECT_EQ(outcome.reason, "wrong_size") << n;
  }
  EXPECT_EQ(decoder.decode(longer, 0, points).reason, "wrong_size");
  EXPECT_EQ(points.size(), 3U);
  EXPECT_EQ(decoder.stats().refused_count(DecodeResult::wrong_size), 6U);
  EXPECT_EQ(decoder.stats().accepted, 0U);
}

// The operator's model wins over a contradicting (known) factory byte, with one notice naming both;
// unknown bytes and return modes are refused.
TEST(LidarVelodynePacket, FactoryBytes) {
  std::mt19937_64 rng(2);
  const test::EncodedPacket packet = test::make_packet(FiringSchedule(make_vlp16(), 0), 0, rng, 0.0);
  std::vector<LidarPoint> points;

  VelodyneDecoder hdl_decoder(make_hdl32e());
  EXPECT_TRUE(hdl_decoder.decode(packet.bytes, 0, points).is_data());
  EXPECT_TRUE(hdl_decoder.decode(packet.bytes, 0, points).is_data());
  EXPECT_EQ(hdl_decoder.stats().product_overridden, 2U);
  const std::vector<std::string> notices = hdl_decoder.take_notices();
  ASSERT_EQ(notices.size(), 1U);
  EXPECT_NE(notices[0].find("VLP-16 (0x22)"), std::string::npos) << notices[0];
  EXPECT_NE(notices[0].find("hdl32e"), std::string::npos) << notices[0];
  EXPECT_TRUE(hdl_decoder.take_notices().empty());

  VelodyneDecoder decoder(make_vlp16());
  auto bytes = packet.bytes;
  bytes[1205] = 0x99;
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "unknown_product");
  bytes = packet.bytes;
  bytes[1204] = 0x3A;
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "unsupported_return_mode");
  bytes[1204] = 0x00;
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "unsupported_return_mode");
  points.clear();
  bytes[1204] = kReturnLast;
  EXPECT_TRUE(decoder.decode(bytes, 0, points).is_data());
  EXPECT_EQ(points.size(), 384U);
  for (const LidarPoint& p : points) {
    EXPECT_EQ(p.echo, kLastReturn);
  }
  EXPECT_EQ(decoder.stats().refused_count(DecodeResult::unknown_product), 1U);
  EXPECT_EQ(decoder.stats().refused_count(DecodeResult::unsupported_return_mode), 2U);
  EXPECT_EQ(decoder.stats().accepted, 1U);
  EXPECT_EQ(decoder.stats().product_overridden, 0U);
  EXPECT_TRUE(decoder.take_notices().empty());
}

TEST(LidarVelodynePacket, RejectsBadBlocksWholeWithoutPartialOutput) {
  std::mt19937_64 rng(4);
  const test::EncodedPacket packet = test::make_packet(FiringSchedule(make_vlp16(), 0), 0, rng, 0.0);
  VelodyneDecoder decoder(make_vlp16());
  std::vector<LidarPoint> points;
  auto bytes = packet.bytes;
  bytes[100 * 11 + 1] = 0xDD;  // the last block's flag: earlier blocks are fine, yet nothing is appended
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "bad_block_flag");
  bytes = packet.bytes;
  bytes[100 * 7 + 2] = 0xA0;  // azimuth 36000 = 0x8CA0
  bytes[100 * 7 + 3] = 0x8C;
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "azimuth_out_of_range");
  bytes = packet.bytes;
  bytes[1203] = 0xFF;  // timestamp >= 3.6e9 us
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "timestamp_out_of_range");
  bytes = packet.bytes;
  bytes[1204] = kReturnDual;  // the schedule's blocks have 12 different azimuths: no pairs
  EXPECT_EQ(decoder.decode(bytes, 0, points).reason, "dual_pair_mismatch");
  EXPECT_TRUE(points.empty());
}

TEST(LidarVelodynePacket, ModelsWithoutPacketFormatAreRefused) {
  EXPECT_THROW(VelodyneDecoder(make_generic(64)), std::invalid_argument);
  std::array<std::uint8_t, kPacketBytes> bytes{};
  EXPECT_THROW(encode_packet(make_generic(32), PacketReturns{}, bytes), std::invalid_argument);
}

TEST(LidarVelodynePacket, ResultNames) {
  EXPECT_EQ(to_string(DecodeResult::accepted), "accepted");
  EXPECT_EQ(to_string(DecodeResult::azimuth_out_of_range), "azimuth_out_of_range");
}

// The packet's hour is the one that puts its time past the hour nearest the reference: across the top of
// the hour both ways, at the half hour, before 1970 and at absurd references (no overflow).
TEST(LidarVelodynePacket, ResolveHourTakesTheNearestHour) {
  const TimeNs day = 20000LL * 24 * kHour;  // 2024-10-04, 00:00 UTC
  const TimeNs eleven = day + 11 * kHour;
  // Received at 10:59:59.95, stamped 0.02 s past the hour: 11:00:00.02 (the sensor's clock is ahead).
  EXPECT_EQ(resolve_hour(20 * kNsPerMs, eleven - 50 * kNsPerMs), eleven + 20 * kNsPerMs);
  // Received at 11:00:00.05, stamped 59:59.98: 10:59:59.98.
  EXPECT_EQ(resolve_hour(kHour - 20 * kNsPerMs, eleven + 50 * kNsPerMs), eleven - 20 * kNsPerMs);
  // Within the hour.
  EXPECT_EQ(resolve_hour(17 * 60 * kNsPerSecond, eleven + 20 * 60 * kNsPerSecond),
            eleven + 17 * 60 * kNsPerSecond);
  // Half an hour either way stays in the reference's hour; a nanosecond more goes to the next or previous.
  EXPECT_EQ(resolve_hour(0, eleven + kHour / 2), eleven);
  EXPECT_EQ(resolve_hour(0, eleven + kHour / 2 + 1), eleven + kHour);
  EXPECT_EQ(resolve_hour(kHour / 2 + 10, eleven), eleven + kHour / 2 + 10 - kHour);
  // Before 1970 (a reference of -0.01 s): the hour before the epoch.
  EXPECT_EQ(resolve_hour(kHour - 5 * kNsPerMs, -10 * kNsPerMs), -5 * kNsPerMs);
  // Absurd references are clamped, not overflowed: the result is some time with the stamp past its hour.
  for (const TimeNs reference : {std::numeric_limits<TimeNs>::max(), std::numeric_limits<TimeNs>::min()}) {
    const TimeNs t = resolve_hour(123 * kNsPerMs, reference);
    const TimeNs past = ((t % kHour) + kHour) % kHour;
    EXPECT_EQ(past, 123 * kNsPerMs);
  }
}

std::vector<std::uint8_t> position_packet(std::uint32_t timestamp_us, const std::string& nmea) {
  std::vector<std::uint8_t> p(512, 0);
  for (int i = 0; i < 4; ++i)  // bytes 198-201, little-endian (the VLP-16 manual's position packet)
    p[198 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(timestamp_us >> (8 * i));
  for (std::size_t i = 0; i < nmea.size(); ++i)
    p[206 + i] = static_cast<std::uint8_t>(nmea[i]);
  return p;
}

TEST(LidarVelodynePacket, PositionPacketTimestampAndSentence) {
  const std::string rmc = "$GPRMC,220243,A,3708.5809,N,12139.7813,W,028.8,158.3,111212,013.8,E,D*14";
  // The sentence is a view of the packet's bytes: the packets are kept while it is read.
  const std::vector<std::uint8_t> gps_packet = position_packet(3'599'999'999U, rmc + "\r\n");
  const auto with_gps = parse_position_packet(gps_packet);
  ASSERT_TRUE(with_gps);
  EXPECT_EQ(with_gps->timestamp_us, 3'599'999'999U);
  EXPECT_EQ(with_gps->nmea, rmc);  // up to the CR
  const std::vector<std::uint8_t> two_sentences = position_packet(7, rmc + "\n$GPGGA");
  EXPECT_EQ(parse_position_packet(two_sentences)->nmea, rmc);
  const std::vector<std::uint8_t> no_gps = position_packet(0, "");
  const auto without = parse_position_packet(no_gps);  // no GPS receiver: NULs
  ASSERT_TRUE(without);
  EXPECT_TRUE(without->nmea.empty());
  // A sentence that fills the packet to its end (306 bytes, no terminator) stops at the packet's end.
  const std::vector<std::uint8_t> full_packet = position_packet(1, std::string(306, 'x'));
  const auto full = parse_position_packet(full_packet);
  ASSERT_TRUE(full);
  EXPECT_EQ(full->nmea.size(), 306U);
  // Refused: a timestamp of an hour or more, any other length.
  EXPECT_FALSE(parse_position_packet(position_packet(3'600'000'000U, rmc)));
  EXPECT_FALSE(parse_position_packet(position_packet(0xffffffffU, rmc)));
  std::vector<std::uint8_t> short_packet = position_packet(5, rmc);
  short_packet.pop_back();
  EXPECT_FALSE(parse_position_packet(short_packet));
  EXPECT_FALSE(parse_position_packet(std::vector<std::uint8_t>(1206, 0)));  // a data packet's length
  EXPECT_FALSE(parse_position_packet({}));
}

}  // namespace
}  // namespace rsu::lidar
