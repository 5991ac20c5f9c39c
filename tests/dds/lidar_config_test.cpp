// SPDX-License-Identifier: Apache-2.0
// rsud.yaml's lidar: section (issue 11): the sensor's keys (calibration, returns, scan phase, time
// source, clock tolerance) and the udp and pcap inputs: defaults, every key, located errors, and the
// calibration file read into the decoder's tables.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>

#include "daemon/config.h"

namespace rsu::daemon {
namespace {

DaemonConfig parse_lidar(const std::string& lidar_body) {
  return parse_config("rsu_id: 1\nlidar:\n  model: vlp32c\n  mount: {x: 0, y: 0, z: 2}\n" + lidar_body,
                      "/etc/rsud/rsud.yaml");
}

std::string lidar_refusal(const std::string& lidar_body) {
  try {
    parse_lidar(lidar_body);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(LidarConfig, DefaultsAreTheSensorsOwn) {
  const DaemonConfig c = parse_lidar("  input: {udp: {}}\n");
  const auto& in = std::get<UdpInput>(c.input);
  EXPECT_EQ(in.port, 2368);  // the Velodyne data port (an Ouster's: 0, its metadata's, rsud asks the decoder)
  EXPECT_EQ(in.auxiliary_port, 0);
  EXPECT_EQ(c.core.time_source, core::TimeSource::kSensor);
  EXPECT_EQ(c.core.clock_tolerance, 100 * kNsPerMs);
  EXPECT_EQ(c.core.sensor_options.returns, lidar::ReturnSelection::both);
  EXPECT_EQ(c.core.sensor_options.rotation_start_azimuth_deg, 0.0);
  EXPECT_TRUE(c.sensor_files.calibration.empty());
  // velodyne_udp is the same input under its older name.
  EXPECT_EQ(std::get<UdpInput>(parse_lidar("  input: {velodyne_udp: {port: 2368}}\n").input).port, 2368);
}

TEST(LidarConfig, ReadsEveryKey) {
  const DaemonConfig c = parse_lidar(
      "  calibration: calib/VLP32.yaml\n"
      "  returns: strongest\n"
      "  scan_phase_deg: 180\n"
      "  time_source: host_receive\n"
      "  clock_tolerance_ms: 20\n"
      "  input:\n"
      "    pcap: {file: captures/road.pcap, pace: max, loop: true, port: 2369, auxiliary_port: 8309}\n");
  EXPECT_EQ(c.sensor_files.calibration, "/etc/rsud/calib/VLP32.yaml");
  EXPECT_EQ(c.core.sensor_options.returns, lidar::ReturnSelection::strongest);
  EXPECT_EQ(c.core.sensor_options.rotation_start_azimuth_deg, 180.0);
  EXPECT_EQ(c.core.time_source, core::TimeSource::kHostReceive);
  EXPECT_EQ(c.core.clock_tolerance, 20 * kNsPerMs);
  const auto& in = std::get<PcapInput>(c.input);
  EXPECT_EQ(in.file, "/etc/rsud/captures/road.pcap");
  EXPECT_EQ(in.pace, PcapInput::Pace::kMax);
  EXPECT_TRUE(in.loop);
  EXPECT_EQ(in.port, 2369);
  EXPECT_EQ(in.auxiliary_port, 8309);
  const DaemonConfig udp = parse_lidar(
      "  input: {udp: {port: 2370, auxiliary_port: 8308, reorder_packets: 3, receive_buffer_bytes: "
      "1048576}}\n");
  EXPECT_EQ(std::get<UdpInput>(udp.input).auxiliary_port, 8308);
  EXPECT_EQ(std::get<UdpInput>(udp.input).receive_buffer_bytes, 1048576U);
  EXPECT_EQ(udp.core.packet_order.depth, 3U);
}

TEST(LidarConfig, ErrorsNameFileLineAndField) {
  EXPECT_NE(lidar_refusal("  returns: dual\n  input: {udp: {}}\n")
                .find("rsud.yaml:5: lidar.returns: expected both, strongest or last"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  time_source: gps\n  input: {udp: {}}\n")
                .find("lidar.time_source: expected sensor or host_receive"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  scan_phase_deg: 360\n  input: {udp: {}}\n")
                .find("lidar.scan_phase_deg: must be within [0, 360)"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  clock_tolerance_ms: 0\n  input: {udp: {}}\n")
                .find("lidar.clock_tolerance_ms: must be > 0"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  input: {pcap: {file: a.pcap, pace: fast}}\n")
                .find("lidar.input.pcap.pace: expected realtime or max"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  input: {pcap: {pace: max}}\n")
                .find("lidar.input.pcap: missing required field \"file\""),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  input: {pcap: {file: a.pcap}, udp: {}}\n").find("exactly one of"),
            std::string::npos);
  EXPECT_NE(lidar_refusal("  input: {udp: {receive_buffer_bytes: 4096}}\n")
                .find("lidar.input.udp.receive_buffer_bytes: must be at least 65536 bytes"),
            std::string::npos);
}

// lidar.calibration is read when the configuration is loaded: its tables replace the built-in ones,
// and a broken file is named with its line.
TEST(LidarConfig, CalibrationFileIsReadIntoTheDecodersTables) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rsu_lidar_config_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file(std::string(RSU_SOURCE_DIR) + "/tests/data/real/nebula_calibration/VLP32.yaml",
                             dir / "VLP32.yaml", std::filesystem::copy_options::overwrite_existing);
  std::ofstream(dir / "broken.yaml") << "lasers:\n  - {laser_id: 0, vert_correction: x, rot_correction: 0}\n";
  auto config_with = [&](const std::string& calibration) {
    std::ofstream(dir / "rsud.yaml") << "rsu_id: 1\nsecurity: {mode: insecure}\nlidar:\n  model: vlp32c\n"
                                     << "  calibration: " << calibration << "\n"
                                     << "  mount: {x: 0, y: 0, z: 2}\n  input: {udp: {}}\n";
    return load_config({(dir / "rsud.yaml").string(), {}});
  };
  const DaemonConfig c = config_with("VLP32.yaml");
  ASSERT_TRUE(c.core.sensor_options.calibrated_model.has_value());
  EXPECT_NEAR(c.core.sensor_options.calibrated_model->azimuth_offset_deg[1], -4.2, 1e-9);
  try {
    config_with("broken.yaml");
    ADD_FAILURE() << "a broken calibration was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.yaml:"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// perception.footprint_track (issue 12): on by default, off when the operator says so; not a boolean: refused
// with the field named.
TEST(LidarConfig, FootprintTrackIsOnUnlessTurnedOff) {
  EXPECT_TRUE(parse_lidar("  input: {udp: {}}\n").core.footprint_track.enabled);
  EXPECT_FALSE(
      parse_lidar("  input: {udp: {}}\nperception: {footprint_track: false}\n").core.footprint_track.enabled);
  EXPECT_NE(lidar_refusal("  input: {udp: {}}\nperception: {footprint_track: sometimes}\n")
                .find("perception.footprint_track"),
            std::string::npos);
}

// perception.prepare_thread (issue 16, latency): the fits and fixes prepared on the event loop unless
// turned on; the mount check's thread is a key of its own.
TEST(LidarConfig, PrepareThreadIsOffUnlessTurnedOn) {
  EXPECT_FALSE(parse_lidar("  input: {udp: {}}\n").prepare_thread);
  const DaemonConfig on = parse_lidar("  input: {udp: {}}\nperception: {prepare_thread: true}\n");
  EXPECT_TRUE(on.prepare_thread);
  EXPECT_TRUE(on.mount_check_thread);
  EXPECT_NE(lidar_refusal("  input: {udp: {}}\nperception: {prepare_thread: 2}\n")
                .find("perception.prepare_thread"),
            std::string::npos);
}

// perception.release_fixed_open (issue 16, latency): on unless turned off; anything but a boolean is
// refused with the field named.
TEST(LidarConfig, ReleaseFixedOpenIsOnUnlessTurnedOff) {
  EXPECT_TRUE(parse_lidar("  input: {udp: {}}\n").core.release_fixed_open);
  EXPECT_FALSE(
      parse_lidar("  input: {udp: {}}\nperception: {release_fixed_open: false}\n").core.release_fixed_open);
  EXPECT_NE(lidar_refusal("  input: {udp: {}}\nperception: {release_fixed_open: soon}\n")
                .find("perception.release_fixed_open"),
            std::string::npos);
}

// perception.joint_release_range_gap_m (issue 16, latency): the clusterer's default unless given; a
// negative or non-numeric gap is refused with the field named.
TEST(LidarConfig, JointReleaseRangeGapIsReadAndChecked) {
  EXPECT_EQ(parse_lidar("  input: {udp: {}}\n").core.sweep.joint_release_range_gap_m,
            perception::SweepConfig{}.joint_release_range_gap_m);
  EXPECT_EQ(parse_lidar("  input: {udp: {}}\nperception: {joint_release_range_gap_m: 2.5}\n")
                .core.sweep.joint_release_range_gap_m,
            2.5);
  for (const char* bad : {"-1", "far"}) {
    EXPECT_NE(lidar_refusal(std::string("  input: {udp: {}}\nperception: {joint_release_range_gap_m: ") +
                            bad + "}\n")
                  .find("perception.joint_release_range_gap_m"),
              std::string::npos)
        << bad;
  }
}

// perception.max_position_sigma_m (issue 12): the fix's cap, the library default unless given (the pilot
// measures the defaults, so the shipped file states that value); not positive, over 10 m or not a number:
// refused with the field named.
TEST(LidarConfig, MaxPositionSigmaIsReadAndChecked) {
  const double fallback = perception::CorrectionConfig{}.max_position_sigma_m;
  EXPECT_EQ(parse_lidar("  input: {udp: {}}\n").core.perception.fix.correction.max_position_sigma_m,
            fallback);
  EXPECT_EQ(parse_lidar("  input: {udp: {}}\nperception: {max_position_sigma_m: 0.5}\n")
                .core.perception.fix.correction.max_position_sigma_m,
            0.5);
  for (const char* bad : {"0", "-1", "11", "far"}) {
    EXPECT_NE(
        lidar_refusal(std::string("  input: {udp: {}}\nperception: {max_position_sigma_m: ") + bad + "}\n")
            .find("perception.max_position_sigma_m"),
        std::string::npos)
        << bad;
  }
  std::ifstream shipped(RSU_SOURCE_DIR "/deploy/rsud.yaml");
  const std::string text((std::istreambuf_iterator<char>(shipped)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(parse_config(text, "deploy/rsud.yaml").core.perception.fix.correction.max_position_sigma_m,
            fallback);
}

}  // namespace
}  // namespace rsu::daemon
