// SPDX-License-Identifier: Apache-2.0
// The Ouster decoder behind the decoder seam (lidar/lidar_decoder.h): the factory, the contract every
// decoder keeps (every payload counted once, IMU packets auxiliary, the packet rhythm for loss
// counting, geometry), on the real captures and on hand-built packets.
#include "lidar/ouster/ouster_lidar_decoder.h"

#include <gtest/gtest.h>

#include <numbers>
#include <stdexcept>

#include "io/yaml_field.h"
#include "tests/lidar/ouster_test_packets.h"
#include "tests/lidar/real_data.h"

namespace rsu::lidar::ouster {
namespace {

constexpr std::uint64_t kStartNs = 5'000'000'000ULL;

std::string metadata_text(const std::string& name) {
  return io::read_text_file(::rsu::lidar::test::real_data_path("ouster/" + name));
}

LidarDecoderOptions options_for(const std::string& metadata_name) {
  LidarDecoderOptions o;
  o.metadata_text = metadata_text(metadata_name);
  o.metadata_source = metadata_name;
  return o;
}

std::string error_of(std::string_view model, const LidarDecoderOptions& o) {
  try {
    make_lidar_decoder(model, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(OusterLidarDecoder, FactoryAndModelNames) {
  for (const char* m : {"os0-128", "os1-16", "os1-32", "os1-64", "os1-128", "os2-32", "os2-128", "ouster"}) {
    EXPECT_TRUE(is_decodable_model(m)) << m;
  }
  for (const char* m : {"os3-32", "os1-48", "os1-", "os1-1280", "OS-1-32", "ouster1"}) {
    EXPECT_FALSE(is_decodable_model(m)) << m;
  }
  const LidarDecoderOptions os1_32 = options_for("OS-1-32-G_v2.1.1_1024x10.json");
  EXPECT_EQ(make_lidar_decoder("os1-32", os1_32)->model_name(), "os1-32");
  EXPECT_EQ(make_lidar_decoder("ouster", os1_32)->model_name(), "os1-32");  // whatever the metadata says
  const std::string other = error_of("os1-128", os1_32);
  EXPECT_NE(other.find("LiDAR model os1-128, but OS-1-32-G_v2.1.1_1024x10.json describes an os1-32"),
            std::string::npos)
      << other;
  EXPECT_NE(
      error_of("os1-32", LidarDecoderOptions{}).find("needs the sensor's metadata JSON (lidar.metadata)"),
      std::string::npos);
  LidarDecoderOptions broken = os1_32;
  broken.metadata_text.replace(broken.metadata_text.find("[12.75, "), 8, "[\"x\", ");
  EXPECT_NE(error_of("os1-32", broken)
                .find("OS-1-32-G_v2.1.1_1024x10.json:4: beam_altitude_angles[0]: "
                      "expected a number"),
            std::string::npos);
  LidarDecoderOptions calibrated = os1_32;
  calibrated.calibrated_model = make_vlp16();
  EXPECT_NE(error_of("os1-32", calibrated).find("Velodyne calibration"), std::string::npos);
  EXPECT_NE(error_of("os9-32", os1_32).find("os0-, os1-, os2-"), std::string::npos);
}

// The tables the fix reasons with (rsud's core: lasers' elevations, azimuth step) are the decoded points':
// an Ouster's from its metadata (32 beams of the file's beam_altitude_angles, 1024 columns a turn).
TEST(OusterLidarDecoder, DecodedSensorModelIsTheMetadatas) {
  const LidarDecoderOptions os1_32 = options_for("OS-1-32-G_v2.1.1_1024x10.json");
  const auto model = decoded_sensor_model("os1-32", os1_32);
  ASSERT_TRUE(model);
  ASSERT_EQ(model->laser_count(), 32U);
  EXPECT_EQ(model->elevation_deg.front(), 12.75);  // the file's first beam altitude
  EXPECT_LT(model->elevation_deg.back(), -10.0);
  EXPECT_NEAR(model->azimuth_step_deg(), 360.0 / 1024.0, 1e-9);
  LidarDecoderOptions broken = os1_32;
  broken.metadata_text.replace(broken.metadata_text.find("[12.75, "), 8, "[\"x\", ");
  EXPECT_FALSE(decoded_sensor_model("os1-32", broken));
  EXPECT_FALSE(decoded_sensor_model("os1-32", LidarDecoderOptions{}));
  // A Velodyne: its calibration's tables where it has one, else the built-in ones.
  EXPECT_EQ(decoded_sensor_model("vlp32c", LidarDecoderOptions{})->elevation_deg,
            make_vlp32c().elevation_deg);
  LidarDecoderOptions calibrated;
  calibrated.calibrated_model = make_vlp16();
  calibrated.calibrated_model->elevation_deg[0] += 0.1;
  EXPECT_EQ(decoded_sensor_model("vlp16", calibrated)->elevation_deg,
            calibrated.calibrated_model->elevation_deg);
}

// The real low-bandwidth OS-1-128 capture through the seam: 192 lidar packets (3 frames) and 30 IMU
// packets, each counted once; the rhythm PacketOrder counts loss from.
TEST(OusterLidarDecoder, RealCaptureThroughTheSeam) {
  auto decoder = make_lidar_decoder("os1-128", options_for("OS-1-128_v2.3.0_1024x10.json"));
  EXPECT_TRUE(decoder->take_notices().empty());  // nothing defaulted in this file
  EXPECT_EQ(decoder->default_ports().data, 7502);
  EXPECT_EQ(decoder->default_ports().auxiliary, 7503);
  const SweepGeometry& g = decoder->geometry();
  EXPECT_DOUBLE_EQ(g.rotation_hz, 10.0);
  EXPECT_EQ(g.packet_period_ns, 1'562'500);  // 16 columns of 1 / (10 Hz x 1024)
  ASSERT_EQ(g.ring_azimuth_offset_rad.size(), 128U);
  EXPECT_NEAR(g.ring_azimuth_offset_rad[0], 4.21 * std::numbers::pi / 180, 1e-12);
  EXPECT_EQ(g.azimuth_lead_rad, 0.0);

  std::vector<LidarPoint> points;
  std::size_t data = 0;
  std::size_t imu = 0;
  std::size_t payloads = 0;
  PacketOutcome previous;
  for (const UdpDatagram& d : ::rsu::lidar::test::read_capture("ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap")) {
    ++payloads;
    const PacketOutcome o = decoder->decode(d.payload, d.time_ns, points);
    if (d.dst.port == 7503) {
      EXPECT_EQ(o.kind, PacketKind::auxiliary);
      EXPECT_EQ(o.reason, "imu");
      ++imu;
      continue;
    }
    ASSERT_TRUE(o.is_data()) << o.reason;
    EXPECT_EQ(o.reason, "accepted");
    EXPECT_LT(o.first_ns, o.next_ns);
    if (data > 0) {
      // The next packet starts when the previous one said, within the sensor's column jitter (< 15 %).
      EXPECT_NEAR(static_cast<double>(o.first_ns - previous.next_ns), 0.0, 0.15 * 97'656);
    }
    previous = o;
    ++data;
  }
  EXPECT_EQ(data, 192U);
  EXPECT_EQ(imu, 30U);
  EXPECT_EQ(decoder->packets_seen(), payloads);
  std::uint64_t notes_points = 0;
  for (const auto& [name, n] : decoder->counters()) {
    if (name == "accepted") {
      EXPECT_EQ(n, 192U);
    } else if (name == "imu") {
      EXPECT_EQ(n, 30U);
    } else if (name == "note.points") {
      notes_points = n;
    } else if (name == "note.frames_complete") {
      EXPECT_EQ(n, 3U);
    } else if (!name.starts_with("note.")) {
      EXPECT_EQ(n, 0U) << name;
    }
  }
  EXPECT_EQ(notes_points, points.size());
  for (const LidarPoint& p : points) {
    ASSERT_EQ(p.echo, kStrongestReturn);
  }
}

TEST(OusterLidarDecoder, NoticesSaidOnce) {
  auto os1_32 = make_lidar_decoder("os1-32", options_for("OS-1-32-G_v2.1.1_1024x10.json"));
  const std::vector<std::string> defaults = os1_32->take_notices();
  ASSERT_EQ(defaults.size(), 1U);
  EXPECT_NE(defaults[0].find("udp_profile_lidar = LEGACY"), std::string::npos) << defaults[0];
  EXPECT_TRUE(os1_32->take_notices().empty());

  const Metadata m = parse_metadata(metadata_text("OS-1-128_v2.3.0_1024x10.json"), "lb.json");
  OusterLidarDecoder d(m, "lb.json");
  test::PacketBuilder p(m, 1, 0, kStartNs, 97'656);
  test::put(p.bytes(), 4, 12345, 3);  // another initialization
  std::vector<LidarPoint> out;
  for (int i = 0; i < 3; ++i) {
    const PacketOutcome o = d.decode(p.bytes(), 0, out);
    EXPECT_EQ(o.kind, PacketKind::refused);
    EXPECT_EQ(o.reason, "wrong_init_id");
  }
  test::put(p.bytes(), 7, 1234, 5);  // and another sensor
  d.decode(p.bytes(), 0, out);
  const std::vector<std::string> notices = d.take_notices();
  ASSERT_EQ(notices.size(), 2U);
  EXPECT_NE(notices[0].find("initialization 12345, but lb.json describes initialization 7109750"),
            std::string::npos)
      << notices[0];
  EXPECT_NE(notices[1].find("serial number 1234, but lb.json describes serial number 122201000998"),
            std::string::npos)
      << notices[1];
  EXPECT_EQ(d.packets_seen(), 4U);
}

// An azimuth window: a packet of only invalid columns carries no points (auxiliary), and the packet
// at the window's end says the next one comes when the sweep is back at the window's start.
TEST(OusterLidarDecoder, AzimuthWindow) {
  Metadata m = parse_metadata(metadata_text("OS-1-32-G_v2.1.1_1024x10.json"), "w.json");
  m.column_window_first = 100;
  m.column_window_last = 199;
  OusterLidarDecoder d(m, "w.json");
  std::vector<LidarPoint> out;
  constexpr std::uint64_t kColumn = 97'656;
  test::PacketBuilder outside(m, 1, 0, kStartNs, kColumn);
  for (int c = 0; c < 16; ++c) {
    outside.set_invalid(c);
  }
  const PacketOutcome none = d.decode(outside.bytes(), 0, out);
  EXPECT_EQ(none.kind, PacketKind::auxiliary);
  EXPECT_EQ(none.reason, "no_valid_column");
  test::PacketBuilder last(m, 1, 192, kStartNs + 192 * kColumn, kColumn);
  for (int c = 8; c < 16; ++c) {
    last.set_invalid(c);  // 200..207 outside
  }
  const PacketOutcome end = d.decode(last.bytes(), 0, out);
  ASSERT_TRUE(end.is_data());
  EXPECT_EQ(end.first_ns, static_cast<TimeNs>(kStartNs + 192 * kColumn));
  // Column 199 is the last; column 100 of the next turn is 925 columns later.
  EXPECT_NEAR(static_cast<double>(end.next_ns - end.first_ns), (7 + 925) * 1e9 / 10240, 1000.0);
  bool seen_no_valid = false;
  for (const auto& [name, n] : d.counters()) {
    if (name == "no_valid_column") {
      EXPECT_EQ(n, 1U);
      seen_no_valid = true;
    }
    if (name == "accepted") {
      EXPECT_EQ(n, 1U);
    }
  }
  EXPECT_TRUE(seen_no_valid);
  EXPECT_EQ(d.packets_seen(), 2U);
}

}  // namespace
}  // namespace rsu::lidar::ouster
