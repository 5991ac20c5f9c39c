// SPDX-License-Identifier: Apache-2.0
// The Velodyne decoder's stream-level behaviour (lidar/velodyne_decoder.h) against truths the test
// knows: the rotation rate measured from the packets at any rpm the sensors run, the return selection
// of dual-return packets, position packets and their $GPRMC, and the real HDL-32E and early-firmware
// VLP-16 captures (tests/data/real/SOURCES.md).
#include "lidar/velodyne_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "lidar/frame_assembler.h"
#include "packet_stream.h"
#include "published_tables.h"
#include "real_data.h"

namespace rsu::lidar {
namespace {

double range_of(const LidarPoint& p) {
  return std::hypot(static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z));
}

double elevation_deg_of(const LidarPoint& p) {
  return std::asin(static_cast<double>(p.z) / range_of(p)) * 180.0 / std::numbers::pi;
}

// 300 and 1200 rpm (the sensors' range), through the decoder built for the nominal 600: the rate it
// reports comes from the packets, and rotations cut from its points hold one turn of firings each.
TEST(VelodyneDecoder, RotationRateIsMeasuredAtAnyRpm) {
  for (const double rpm : {300.0, 600.0, 1200.0}) {
    SensorModel spinning = make_vlp16();
    spinning.rpm = rpm;
    const FiringSchedule schedule(spinning, 5 * kNsPerSecond, 17.0);
    VelodyneDecoder decoder(make_vlp16());  // nominal 600 rpm
    FrameAssembler assembler;
    std::vector<LidarFrame> frames;
    std::mt19937_64 rng(3);
    const auto packets = static_cast<std::int64_t>(3.5 / (rpm / 60.0) / 1.327104e-3);  // 3.5 rotations
    for (std::int64_t k = 0; k < packets; ++k) {
      const test::EncodedPacket packet = test::make_packet(schedule, k, rng, 0.0);
      std::vector<LidarPoint> points;
      ASSERT_TRUE(decoder.decode(packet.bytes, packet.returns.blocks.first_firing_ns, points).is_data());
      for (std::size_t i = 0; i < points.size(); ++i) {
        // Where the rotor really was: the schedule's own firing azimuths.
        ASSERT_NEAR(std::remainder(static_cast<double>(points[i].azimuth_rad) - packet.firings[i].azimuth_rad,
                                   2.0 * std::numbers::pi),
                    0.0, 3e-4)
            << rpm << " rpm";
      }
      assembler.set_rotation_hz(decoder.geometry().rotation_hz);
      for (LidarFrame& f : assembler.add(points))
        frames.push_back(std::move(f));
    }
    EXPECT_NEAR(decoder.geometry().rotation_hz, rpm / 60.0, 0.002 * rpm / 60.0) << rpm << " rpm";
    ASSERT_GE(frames.size(), 2U) << rpm << " rpm";
    // A whole rotation: 1 / rate of firing sequences, 16 lasers each.
    const double per_rotation = 16.0 / (rpm / 60.0) / 55.296e-6;
    for (const LidarFrame& f : frames) {
      EXPECT_NEAR(static_cast<double>(f.points.size()), per_rotation, 0.01 * per_rotation) << rpm << " rpm";
      EXPECT_NEAR(to_seconds(f.end_ns - f.start_ns), 60.0 / rpm, 0.01 * 60.0 / rpm) << rpm << " rpm";
    }
  }
}

// Dual return (0x39): the test's own pairs of echoes, and each selection keeps what it says.
TEST(VelodyneDecoder, DualReturnSelection) {
  const SensorModel model = make_vlp16();
  std::mt19937_64 rng(5);
  const FiringSchedule schedule(model, 0);
  test::EncodedPacket packet = test::make_packet(schedule, 0, rng, 0.0);
  // Pairs: block 2k (last echo) and 2k + 1 (the other), same azimuths. Firings by channel: (a) one
  // echo reported twice, (b) the other stronger, (c) the last stronger, (d) nothing.
  PacketReturns& r = packet.returns;
  r.blocks.dual_return = true;
  for (std::size_t b = 1; b < 12; b += 2)
    r.blocks.azimuth_cdeg[b] = r.blocks.azimuth_cdeg[b - 1];
  std::map<std::string, int> expected = {{"both", 0}, {"strongest", 0}, {"last", 0}};
  for (std::size_t b = 0; b < 12; b += 2) {
    for (std::size_t c = 0; c < 32; ++c) {
      const int kind = static_cast<int>(c % 4);
      r.distance_raw[b][c] = kind == 3 ? 0 : static_cast<std::uint16_t>(2000 + c);
      r.distance_raw[b + 1][c] = kind == 0   ? r.distance_raw[b][c]
                                 : kind == 3 ? 0
                                             : static_cast<std::uint16_t>(1000 + c);
      r.reflectivity[b][c] = kind == 1 ? 10 : 200;
      r.reflectivity[b + 1][c] = kind == 1 ? 90 : 20;
      expected["both"] += kind == 0 ? 1 : kind == 3 ? 0 : 2;
      expected["strongest"] += kind == 3 ? 0 : 1;
      expected["last"] += kind == 3 ? 0 : 1;
    }
  }
  encode_packet(model, r, packet.bytes);
  ASSERT_EQ(packet.bytes[1204], kReturnDual);
  for (const auto& [name, count] : expected) {
    VelodyneDecoder decoder(model, *return_selection_by_name(name));
    std::vector<LidarPoint> points;
    ASSERT_TRUE(decoder.decode(packet.bytes, 0, points).is_data());
    EXPECT_EQ(static_cast<int>(points.size()), count) << name;
    std::map<std::uint8_t, int> by_echo;
    for (const LidarPoint& p : points)
      ++by_echo[p.echo];
    // 8 firings of each kind in each of the 6 pairs. (a) and (c)'s last echo are both the strongest and
    // the last; (b)'s last is the last only and its other the strongest; (c)'s other is neither.
    const int each = 6 * 8;
    EXPECT_EQ(by_echo[kStrongestReturn | kLastReturn], 2 * each) << name;
    EXPECT_EQ(by_echo[kLastReturn], name == "strongest" ? 0 : each) << name;
    EXPECT_EQ(by_echo[kStrongestReturn], name == "last" ? 0 : each) << name;
    EXPECT_EQ(by_echo[0], name == "both" ? each : 0) << name;
    for (const LidarPoint& p : points) {
      if (name == "strongest") {
        EXPECT_TRUE(p.echo & kStrongestReturn);
      }
      if (name == "last") {
        EXPECT_TRUE(p.echo & kLastReturn);
      }
    }
    EXPECT_EQ(decoder.stats().no_return, 6U * 8U);
  }
  // Packets of a dual-return stream span 6 firing groups: the packet period halves.
  VelodyneDecoder decoder(model);
  std::vector<LidarPoint> points;
  const PacketOutcome outcome = decoder.decode(packet.bytes, 0, points);
  EXPECT_EQ(outcome.next_ns - outcome.first_ns, 6 * 110'592);
  EXPECT_EQ(decoder.geometry().packet_period_ns, 6 * 110'592);
}

TEST(VelodyneDecoder, NmeaRecommendedMinimum) {
  // The real HDL-32E capture's sentence (GPS 2012-12-11 22:02:43 UTC).
  const std::string real = "$GPRMC,220243,A,3708.5809,N,12139.7813,W,028.8,158.3,111212,013.8,E,D*03";
  ASSERT_TRUE(nmea_rmc_utc(real).has_value());
  EXPECT_EQ(*nmea_rmc_utc(real), 1'355'263'363LL * kNsPerSecond);
  // Another talker (GNSS), a two-digit year of the last century.
  EXPECT_EQ(nmea_rmc_utc("$GNRMC,235959,A,3708.5809,N,12139.7813,W,028.8,158.3,311299,013.8,E,D*18"),
            946'684'799LL * kNsPerSecond);
  // Status V (no fix, checksum right), a wrong checksum, too few fields, nothing, another sentence.
  EXPECT_FALSE(nmea_rmc_utc("$GPRMC,220243,V,3708.5809,N,12139.7813,W,028.8,158.3,111212,013.8,E,D*14"));
  EXPECT_FALSE(nmea_rmc_utc("$GPRMC,220243,A,3708.5809,N,12139.7813,W,028.8,158.3,111212,013.8,E,D*04"));
  EXPECT_FALSE(nmea_rmc_utc("$GPRMC,220243,A,3708.5809,N*12"));
  EXPECT_FALSE(nmea_rmc_utc(""));
  EXPECT_FALSE(nmea_rmc_utc("$GPGGA,220243,3708.5809,N,12139.7813,W,1,08,0.9,545.4,M,46.9,M,,*47"));
}

// The real HDL-32E capture (vehicle-mounted, with a GPS): its position packets' $GPRMC agrees with
// their timestamps, so the data packets' hour is the GPS's (2012-12-11 22:xx UTC) whatever the
// reference time says; its points are on the HDL-32E's 32 rings at their elevations.
TEST(VelodyneDecoder, RealHdl32eTakesItsHourFromTheGps) {
  VelodyneDecoder decoder(make_hdl32e());
  std::vector<LidarPoint> points;
  const TimeNs hour_2012 = 1'355'263'200LL * kNsPerSecond;  // 2012-12-11 22:00:00 UTC
  const TimeNs wrong_reference = hour_2012 + 25 * 60 * kNsPerSecond + kNsPerSecond;  // 22:25: off by 22 min
  for (const UdpDatagram& d : test::read_capture("rlu_hdl32e_driving_876pkts.pcap")) {
    points.clear();
    const PacketOutcome o = decoder.decode(d.payload, wrong_reference, points);
    if (!o.is_data())
      continue;
    // Before the first position packet the wrong reference decides (the nearest hour is right anyway);
    // after it, the GPS: the points' times lie within 22:02-22:04.
    for (const LidarPoint& p : points) {
      ASSERT_GE(p.time_ns, hour_2012 + 2 * 60 * kNsPerSecond);
      ASSERT_LT(p.time_ns, hour_2012 + 4 * 60 * kNsPerSecond);
      ASSERT_LT(p.ring, 32);
      if (range_of(p) > 1.0) {
        EXPECT_NEAR(elevation_deg_of(p), test::kHdl32eElevationDeg[p.ring], 0.01);
      }
    }
  }
  EXPECT_EQ(decoder.stats().accepted, 876U);
  EXPECT_EQ(decoder.stats().position, 100U);
  EXPECT_GT(decoder.stats().gps_hours, 800U);
  EXPECT_NEAR(decoder.geometry().rotation_hz, 11.72, 0.05);  // ~703 rpm, from the packets
  // A reference more than half an hour off: the nearest hour would be wrong; the GPS keeps it right.
  VelodyneDecoder far(make_hdl32e());
  const TimeNs far_reference = hour_2012 + 40 * 60 * kNsPerSecond;
  TimeNs last_time = 0;
  for (const UdpDatagram& d : test::read_capture("rlu_hdl32e_driving_876pkts.pcap")) {
    points.clear();
    if (far.decode(d.payload, far_reference, points).is_data() && !points.empty())
      last_time = points.back().time_ns;
  }
  EXPECT_GE(last_time, hour_2012);
  EXPECT_LT(last_time, hour_2012 + 3600 * kNsPerSecond);
}

// Early VLP-16 firmware: factory byte 0x21 (HDL-32E). Configured as a VLP-16 it decodes on the VLP-16's
// rings with one notice naming both; its position packets (no GPS) are counted, never refused.
TEST(VelodyneDecoder, RealEarlyFirmwareVlp16DecodesAsConfigured) {
  VelodyneDecoder decoder(make_vlp16());
  std::vector<LidarPoint> points;
  for (const UdpDatagram& d : test::read_capture("rlu_vlp16_earlyfw_84pkts.pcap")) {
    const PacketOutcome o = decoder.decode(d.payload, d.time_ns, points);
    EXPECT_NE(o.kind, PacketKind::refused) << o.reason;
  }
  EXPECT_EQ(decoder.stats().accepted, 84U);
  EXPECT_EQ(decoder.stats().position, 16U);
  EXPECT_EQ(decoder.stats().product_overridden, 84U);
  for (const LidarPoint& p : points) {
    ASSERT_LT(p.ring, 16);
    if (range_of(p) > 1.0) {
      EXPECT_NEAR(elevation_deg_of(p), test::kVlp16ElevationDeg[p.ring], 0.01);
    }
  }
  const std::vector<std::string> notices = decoder.take_notices();
  ASSERT_EQ(notices.size(), 1U);
  EXPECT_NE(notices[0].find("HDL-32E (0x21)"), std::string::npos) << notices[0];
  EXPECT_NE(notices[0].find("vlp16"), std::string::npos) << notices[0];
}

}  // namespace
}  // namespace rsu::lidar
