// SPDX-License-Identifier: Apache-2.0
// Ouster decoding against hand-built packets (tests/lidar/ouster_test_packets.h, from the manual's
// layout) whose points the test computes itself: the manual's range-to-xyz written out directly, and
// a few beams whose answer is known by hand. Refusals and frame sequencing, one reason at a time.
#include "lidar/ouster/ouster_decoder.h"

#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>
#include <functional>
#include <stdexcept>

#include "common/angles.h"
#include "io/yaml_field.h"
#include "tests/lidar/ouster_test_packets.h"
#include "tests/lidar/real_data.h"

namespace rsu::lidar::ouster {
namespace {

using test::PacketBuilder;

constexpr std::uint64_t kT0 = 5'000'000'000ULL;
constexpr std::uint64_t kDt = 97'656;  // ns per column at 1024 x 10 Hz

Metadata real_metadata(const std::string& name) {
  return parse_metadata(io::read_text_file(::rsu::lidar::test::real_data_path("ouster/" + name)), name);
}

// 16 beams: row 0 level and straight (azimuth 0), row 1 at +10 deg, row 2 4 deg clockwise, the rest
// spread; beam origin 20 mm; sensor frame 40 mm below the lidar origin.
Metadata simple_metadata(const std::string& mode = "1024x10", int columns = 1024) {
  const std::string json = R"({"prod_line": "OS-1-16-A0", "lidar_mode": ")" + mode + R"(",
    "beam_altitude_angles": [0, 10, 0, 3, 2, 1, -1, -2, -3, -4, -5, -6, -7, -8, -9, -10],
    "beam_azimuth_angles": [0, 0, 4, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1],
    "lidar_origin_to_beam_origin_mm": 20,
    "lidar_to_sensor_transform": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 40, 0, 0, 0, 1],
    "data_format": {"columns_per_frame": )" +
                           std::to_string(columns) +
                           R"(, "columns_per_packet": 16, "pixels_per_column": 16}})";
  return parse_metadata(json, "simple.json");
}

// The firmware manual's "range to XYZ" in the lidar frame, then lidar_to_sensor: metres.
Eigen::Vector3d manual_point(const Metadata& m, int row, int column, double range_mm) {
  const double n = m.beam_origin_x_mm;
  const double encoder = 2.0 * kPi * (1.0 - static_cast<double>(column) / m.columns_per_frame);
  const double azimuth = -m.beam_azimuth_deg[static_cast<std::size_t>(row)] * kPi / 180.0;
  const double altitude = m.beam_altitude_deg[static_cast<std::size_t>(row)] * kPi / 180.0;
  const Eigen::Vector4d lidar(
      (range_mm - n) * std::cos(encoder + azimuth) * std::cos(altitude) + n * std::cos(encoder),
      (range_mm - n) * std::sin(encoder + azimuth) * std::cos(altitude) + n * std::sin(encoder),
      (range_mm - n) * std::sin(altitude), 1.0);
  return (m.lidar_to_sensor * lidar).head<3>() * 1e-3;
}

std::vector<LidarPoint> decode_one(Decoder& d, std::vector<std::uint8_t>& packet, PacketResult expected) {
  std::vector<LidarPoint> out;
  EXPECT_EQ(d.decode(packet, out), expected) << to_string(d.last_packet().result);
  return out;
}

TEST(OusterDecoder, BeamsKnownByHand) {
  const Metadata m = simple_metadata();
  Decoder d(m);
  PacketBuilder p(m, 7, 512, kT0, kDt);  // column 512 of 1024 looks forward (away from the connector)
  p.set_range(0, 0, 10'000);             // level, azimuth 0: straight ahead, 10 m
  p.set_range(0, 1, 10'000);             // 10 deg up
  p.set_range(0, 2, 10'000);             // 4 deg clockwise of straight ahead
  p.set_range(4, 0, 10'000);             // column 516: 4 columns (1.40625 deg) further clockwise
  const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
  ASSERT_EQ(pts.size(), 4U);
  // Straight ahead: the range is measured from the lidar origin, 40 mm above the base.
  EXPECT_NEAR(pts[0].x, 10.0, 1e-5);
  EXPECT_NEAR(pts[0].y, 0.0, 1e-5);
  EXPECT_NEAR(pts[0].z, 0.040, 1e-6);
  EXPECT_NEAR(pts[0].azimuth_rad, 0.0, 1e-6);
  EXPECT_EQ(pts[0].ring, 0);
  EXPECT_EQ(pts[0].time_ns, static_cast<TimeNs>(kT0));
  EXPECT_FLOAT_EQ(pts[0].intensity, 100.0F);
  // Up 10 deg: from the beam origin, 20 mm ahead of the lidar origin, over range - 20 mm.
  EXPECT_NEAR(pts[1].x, 0.020 + 9.980 * std::cos(10 * kPi / 180), 1e-5);
  EXPECT_NEAR(pts[1].y, 0.0, 1e-5);
  EXPECT_NEAR(pts[1].z, 0.040 + 9.980 * std::sin(10 * kPi / 180), 1e-5);
  EXPECT_EQ(pts[1].ring, 1);
  // 4 deg clockwise seen from above: to the right (y < 0).
  EXPECT_NEAR(pts[2].x, 0.020 + 9.980 * std::cos(4 * kPi / 180), 1e-5);
  EXPECT_NEAR(pts[2].y, -9.980 * std::sin(4 * kPi / 180), 1e-5);
  EXPECT_NEAR(pts[2].azimuth_rad, 4 * kPi / 180, 1e-6);
  // Four columns later, 4 x 360 / 1024 deg clockwise, 4 column periods later.
  const double a = 4 * 2 * kPi / 1024;
  EXPECT_NEAR(pts[3].x, 10.0 * std::cos(a), 1e-5);
  EXPECT_NEAR(pts[3].y, -10.0 * std::sin(a), 1e-5);
  EXPECT_NEAR(pts[3].azimuth_rad, a, 1e-6);
  EXPECT_EQ(pts[3].time_ns, static_cast<TimeNs>(kT0 + 4 * kDt));
}

TEST(OusterDecoder, QuarterTurnsOfTheHead) {
  const Metadata m = simple_metadata();
  Decoder d(m);
  std::vector<LidarPoint> pts;
  for (const int column : {0, 256, 768}) {  // backwards, left, right (clockwise from backwards)
    PacketBuilder p(m, 7, column, kT0 + static_cast<std::uint64_t>(column) * kDt, kDt);
    p.set_range(0, 0, 5'000);
    ASSERT_EQ(d.decode(p.bytes(), pts), PacketResult::accepted);
  }
  ASSERT_EQ(pts.size(), 3U);
  EXPECT_NEAR(pts[0].x, -5.0, 1e-5);
  EXPECT_NEAR(pts[0].y, 0.0, 1e-5);
  EXPECT_NEAR(pts[0].azimuth_rad, kPi, 1e-6);
  EXPECT_NEAR(pts[1].x, 0.0, 1e-5);
  EXPECT_NEAR(pts[1].y, 5.0, 1e-5);
  EXPECT_NEAR(pts[1].azimuth_rad, 1.5 * kPi, 1e-6);
  EXPECT_NEAR(pts[2].y, -5.0, 1e-5);
  EXPECT_NEAR(pts[2].azimuth_rad, 0.5 * kPi, 1e-6);
}

// Every pixel of real metadata (both beam tables, its own origin offset and transform) against the
// manual's formula, in each profile's units.
TEST(OusterDecoder, EveryPixelMatchesTheManualFormula) {
  for (const char* name : {"OS-1-32-G_v2.1.1_1024x10.json", "OS-1-128_v2.3.0_1024x10.json",
                           "OS-2-128-U1_v2.3.0_1024x10.json", "OS-0-128-U1_v2.3.0_1024x10.json"}) {
    SCOPED_TRACE(name);
    const Metadata m = real_metadata(name);
    Decoder d(m, DecoderConfig{.min_range_m = 0.0});
    const int first_column = 333 - 333 % m.columns_per_packet;
    PacketBuilder p(m, 42, first_column, kT0, kDt);
    for (int c = 0; c < m.columns_per_packet; ++c) {
      for (int row = 0; row < m.pixels_per_column; ++row) {
        p.set_range(c, row, static_cast<std::uint32_t>(8 * (100 + 37 * row + 5 * c)), 7, /*flag_bits=*/true);
      }
    }
    const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
    ASSERT_EQ(pts.size(), static_cast<std::size_t>(m.columns_per_packet * m.pixels_per_column));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const int c = static_cast<int>(i) / m.pixels_per_column;
      const int row = static_cast<int>(i) % m.pixels_per_column;
      const Eigen::Vector3d want = manual_point(m, row, first_column + c, 8.0 * (100 + 37 * row + 5 * c));
      ASSERT_NEAR(pts[i].x, want.x(), 2e-6) << "column " << c << " row " << row;
      ASSERT_NEAR(pts[i].y, want.y(), 2e-6);
      ASSERT_NEAR(pts[i].z, want.z(), 2e-6);
      ASSERT_EQ(pts[i].ring, row);
      ASSERT_EQ(pts[i].time_ns, static_cast<TimeNs>(kT0 + static_cast<std::uint64_t>(c) * kDt));
    }
  }
}

// A sensor mounted tilted in its own metadata (lidar_to_sensor not only about z): the azimuth is then
// the direction's, not the column's angle plus the beam's offset.
TEST(OusterDecoder, TiltedLidarToSensorTransform) {
  Metadata m = simple_metadata();
  const double tilt = 10 * kPi / 180;  // about x
  Eigen::Matrix4d t = m.lidar_to_sensor;
  t.block<3, 3>(0, 0) = Eigen::Matrix3d(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX())) *
                        m.lidar_to_sensor.block<3, 3>(0, 0);
  m.lidar_to_sensor = t;
  Decoder d(m);
  PacketBuilder p(m, 7, 200, kT0, kDt);
  p.set_range(3, 2, 20'000);
  p.set_range(3, 2 + 1, 20'000);
  const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
  ASSERT_EQ(pts.size(), 2U);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const int row = 2 + static_cast<int>(i);
    const Eigen::Vector3d want = manual_point(m, row, 203, 20'000);
    EXPECT_NEAR(pts[i].x, want.x(), 1e-5);
    EXPECT_NEAR(pts[i].y, want.y(), 1e-5);
    EXPECT_NEAR(pts[i].z, want.z(), 1e-5);
    const Eigen::Vector3d beam = want - manual_point(m, row, 203, 10'000);
    EXPECT_NEAR(
        std::remainder(static_cast<double>(pts[i].azimuth_rad) - std::atan2(-beam.y(), beam.x()), 2 * kPi),
        0.0, 1e-5);
  }
}

TEST(OusterDecoder, NoReturnAndMinimumRange) {
  const Metadata m = simple_metadata();
  Decoder d(m);  // 0.5 m
  PacketBuilder p(m, 7, 0, kT0, kDt);
  p.set_range(0, 0, 499);
  p.set_range(0, 1, 500);
  p.set_range(1, 0, 1);
  const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
  ASSERT_EQ(pts.size(), 1U);
  EXPECT_EQ(pts[0].ring, 1);
  EXPECT_EQ(d.stats().too_close, 2U);
  EXPECT_EQ(d.stats().no_return, 16U * 16U - 3U);
  EXPECT_EQ(d.stats().points, 1U);
  EXPECT_THROW(Decoder(m, DecoderConfig{.min_range_m = -1.0}), std::invalid_argument);
  EXPECT_THROW(Decoder(m, DecoderConfig{.min_range_m = std::nan("")}), std::invalid_argument);
}

TEST(OusterDecoder, ReflectivityBecomesIntensityClamped) {
  const Metadata m = real_metadata("OS-1-32-G_v2.1.1_1024x10.json");  // LEGACY: 16-bit reflectivity
  Decoder d(m);
  PacketBuilder p(m, 1, 0, kT0, kDt);
  p.set_range(0, 0, 2'000, 200);
  p.set_range(0, 1, 2'000, 255);
  const std::size_t at = p.pixel_at(0, 2);
  p.set_range(0, 2, 2'000);
  test::put(p.bytes(), at + 4, 1000, 2);
  const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
  ASSERT_EQ(pts.size(), 3U);
  EXPECT_FLOAT_EQ(pts[0].intensity, 200.0F);
  EXPECT_FLOAT_EQ(pts[1].intensity, 255.0F);
  EXPECT_FLOAT_EQ(pts[2].intensity, 255.0F);
}

TEST(OusterDecoder, RefusalsByReason) {
  const Metadata lb = real_metadata("OS-1-128_v2.3.0_1024x10.json");  // eUDP, with serial and init id
  const Metadata legacy = real_metadata("OS-1-32-G_v2.1.1_1024x10.json");
  struct Case {
    const Metadata* m;
    std::function<void(PacketBuilder&)> damage;
    PacketResult expected;
  };
  const std::vector<Case> cases = {
      {&lb, [](PacketBuilder& p) { p.bytes().pop_back(); }, PacketResult::wrong_size},
      {&lb, [](PacketBuilder& p) { p.bytes().resize(48); }, PacketResult::imu_packet},
      {&lb, [](PacketBuilder& p) { p.bytes().clear(); }, PacketResult::wrong_size},
      {&lb, [](PacketBuilder& p) { test::put(p.bytes(), 0, 2, 2); }, PacketResult::not_lidar_packet},
      {&lb, [](PacketBuilder& p) { test::put(p.bytes(), 7, 122201000999ULL, 5); },
       PacketResult::wrong_serial},
      {&lb, [](PacketBuilder& p) { test::put(p.bytes(), 4, 7109751, 3); }, PacketResult::wrong_init_id},
      {&lb, [](PacketBuilder& p) { p.set_timestamp(3, 1ULL << 63); }, PacketResult::bad_timestamp},
      {&lb, [](PacketBuilder& p) { p.set_measurement_id(15, 1024); }, PacketResult::bad_measurement_id},
      {&lb, [](PacketBuilder& p) { p.set_measurement_id(5, 99); }, PacketResult::bad_measurement_id},
      {&legacy, [](PacketBuilder& p) { p.set_column_frame_id(9, 8); }, PacketResult::frame_id_mismatch},
      {&legacy, [](PacketBuilder& p) { p.set_measurement_id(0, 2000); }, PacketResult::bad_measurement_id},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    Decoder d(*cases[i].m);
    PacketBuilder p(*cases[i].m, 7, 64, kT0, kDt);
    p.set_range(0, 0, 3'000);
    cases[i].damage(p);
    const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), cases[i].expected);
    EXPECT_TRUE(pts.empty());
    EXPECT_EQ(d.stats().packets(), 1U);
    EXPECT_EQ(d.stats().accepted, 0U);
    EXPECT_EQ(d.stats().rejected(), cases[i].expected == PacketResult::imu_packet ? 0U : 1U);
    EXPECT_EQ(d.stats().imu_packets, cases[i].expected == PacketResult::imu_packet ? 1U : 0U);
    EXPECT_EQ(d.stats().frames, 0U);
    EXPECT_FALSE(to_string(cases[i].expected).empty());
  }
}

TEST(OusterDecoder, InitIdCheckCanBeRelaxed) {
  const Metadata lb = real_metadata("OS-1-128_v2.3.0_1024x10.json");
  Decoder d(lb, DecoderConfig{.check_initialization_id = false});
  PacketBuilder p(lb, 7, 0, kT0, kDt);
  test::put(p.bytes(), 4, 1234, 3);
  decode_one(d, p.bytes(), PacketResult::accepted);
}

TEST(OusterDecoder, InvalidColumnsGiveNoPoints) {
  const Metadata m = simple_metadata();
  Decoder d(m);
  PacketBuilder p(m, 7, 32, kT0, kDt);
  for (int c = 0; c < 16; ++c) {
    p.set_range(c, 0, 3'000);
  }
  p.set_invalid(0);
  p.set_invalid(7);  // a hole inside the packet: still consecutive ids around it
  p.set_invalid(15);
  const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
  EXPECT_EQ(pts.size(), 13U);
  EXPECT_EQ(d.stats().columns_invalid, 3U);
  EXPECT_EQ(d.stats().columns_decoded, 13U);
  EXPECT_EQ(d.last_packet().first_column, 33);
  EXPECT_EQ(d.last_packet().last_column, 46);
  // A packet of only invalid columns is accepted, with nothing in it.
  PacketBuilder empty(m, 7, 48, kT0, kDt);
  for (int c = 0; c < 16; ++c) {
    empty.set_invalid(c);
  }
  EXPECT_TRUE(decode_one(d, empty.bytes(), PacketResult::accepted).empty());
  EXPECT_EQ(d.last_packet().first_column, -1);
}

// Whole frames of a 512x20 sensor: boundaries, completeness, a lost packet, late and repeated ones.
TEST(OusterDecoder, FrameSequence) {
  const Metadata m = simple_metadata("512x20", 512);
  Decoder d(m);
  std::vector<LidarPoint> pts;
  const auto send = [&](std::uint16_t frame, int first_column) {
    PacketBuilder p(m, frame, first_column,
                    kT0 + static_cast<std::uint64_t>(frame * 512 + first_column) * kDt, kDt);
    for (int c = 0; c < 16; ++c) {
      p.set_range(c, 3, 4'000);
    }
    return d.decode(p.bytes(), pts);
  };
  // Frame 65535 from column 256 (joined mid-frame: nothing counted as lost), wrapping to frame 0.
  for (int c = 256; c < 512; c += 16) {
    ASSERT_EQ(send(65535, c), PacketResult::accepted);
    EXPECT_EQ(d.last_packet().begins_frame, c == 256);
    EXPECT_EQ(d.last_packet().completes_frame, c == 496);
  }
  EXPECT_EQ(d.stats().frames_complete, 0U);  // its first half was never seen
  for (int c = 0; c < 512; c += 16) {
    if (c == 160) {
      continue;  // lost
    }
    ASSERT_EQ(send(0, c), PacketResult::accepted);
    EXPECT_EQ(d.last_packet().begins_frame, c == 0);
  }
  EXPECT_EQ(d.stats().columns_skipped, 16U);
  EXPECT_EQ(d.stats().frames_complete, 0U);
  EXPECT_EQ(send(0, 160), PacketResult::column_behind);  // the lost packet turns up late
  EXPECT_EQ(send(0, 496), PacketResult::column_behind);  // a duplicate
  for (int c = 0; c < 512; c += 16) {
    ASSERT_EQ(send(1, c), PacketResult::accepted);
  }
  EXPECT_EQ(d.stats().frames_complete, 1U);
  EXPECT_EQ(send(0, 0), PacketResult::frame_behind);
  EXPECT_EQ(send(1, 0), PacketResult::column_behind);
  // Frame 2 loses its last packet, frame 3 its first: 32 columns skipped, no jump.
  for (int c = 0; c < 496; c += 16) {
    ASSERT_EQ(send(2, c), PacketResult::accepted);
  }
  ASSERT_EQ(send(3, 16), PacketResult::accepted);
  EXPECT_TRUE(d.last_packet().begins_frame);
  EXPECT_EQ(d.stats().columns_skipped, 48U);
  EXPECT_EQ(d.stats().frame_id_jumps, 0U);
  ASSERT_EQ(send(9, 0), PacketResult::accepted);  // frames 4..8 lost, or a restart
  EXPECT_EQ(d.stats().frame_id_jumps, 1U);
  EXPECT_EQ(d.stats().frames, 6U);
  EXPECT_EQ(d.stats().accepted, 16U + 31U + 32U + 31U + 1U + 1U);
  EXPECT_EQ(d.stats().rejected(), 4U);
  // No column is filled in: one point per received column.
  EXPECT_EQ(pts.size(), 16U * d.stats().accepted);
  EXPECT_EQ(d.stats().columns_decoded, pts.size());
}

// An azimuth window: the frame is complete when the window's columns arrived.
TEST(OusterDecoder, ColumnWindowFrames) {
  Metadata m = simple_metadata();
  m.column_window_first = 96;
  m.column_window_last = 200;  // packets 96..207: the last one partly outside
  Decoder d(m);
  std::vector<LidarPoint> pts;
  for (int c = 96; c < 208; c += 16) {
    PacketBuilder p(m, 3, c, kT0 + static_cast<std::uint64_t>(c) * kDt, kDt);
    if (c == 192) {
      for (int k = 9; k < 16; ++k) {
        p.set_invalid(k);  // 201..207 outside the window
      }
    }
    ASSERT_EQ(d.decode(p.bytes(), pts), PacketResult::accepted);
  }
  EXPECT_TRUE(d.last_packet().completes_frame);
  EXPECT_EQ(d.stats().frames_complete, 1U);  // joined at the window's first column: all 105 arrived
  for (int c = 96; c < 208; c += 16) {
    PacketBuilder p(m, 4, c, kT0 + static_cast<std::uint64_t>(1024 + c) * kDt, kDt);
    ASSERT_EQ(d.decode(p.bytes(), pts), PacketResult::accepted);  // 201..207 valid this time
  }
  EXPECT_EQ(d.stats().frames_complete, 2U);
  EXPECT_EQ(d.stats().columns_skipped, 0U);
  EXPECT_EQ(d.stats().frames, 2U);
}

TEST(OusterDecoder, ProfileUnitsAndFlagBitsIgnored) {
  // RNG15: 15 bits of 8 mm; RNG19: 19 bits of 1 mm; LEGACY: 20 bits of 1 mm; flag bits above ignored.
  for (const char* name :
       {"OS-1-128_v2.3.0_1024x10.json", "OS-2-128-U1_v2.3.0_1024x10.json", "OS-1-32-G_v2.1.1_1024x10.json"}) {
    SCOPED_TRACE(name);
    const Metadata m = real_metadata(name);
    Decoder d(m);
    PacketBuilder p(m, 1, 512, kT0, kDt);
    const std::uint32_t longest = m.profile == UdpProfile::rng15_rfl8_nir8          ? 0x7FFF * 8
                                  : m.profile == UdpProfile::rng19_rfl8_sig16_nir16 ? 0x7FFFF
                                                                                    : 0xFFFFF;
    p.set_range(0, 0, longest, 1, true);
    const std::vector<LidarPoint> pts = decode_one(d, p.bytes(), PacketResult::accepted);
    ASSERT_EQ(pts.size(), 1U);
    const Eigen::Vector3d want = manual_point(m, 0, 512, longest);
    EXPECT_NEAR(pts[0].x, want.x(), 1e-3);
    EXPECT_NEAR(pts[0].z, want.z(), 1e-3);
  }
}

}  // namespace
}  // namespace rsu::lidar::ouster
