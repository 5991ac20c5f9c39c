// SPDX-License-Identifier: Apache-2.0
// Ouster metadata JSON against the real files in tests/data/real/ouster (SOURCES.md): what each holds
// is read off the file itself, and the same sensor's flat and nested files must give one geometry.
#include "lidar/ouster/ouster_metadata.h"

#include <gtest/gtest.h>

#include <string>

#include "io/yaml_field.h"
#include "lidar/ouster/ouster_geometry.h"
#include "tests/lidar/real_data.h"

namespace rsu::lidar::ouster {
namespace {

std::string data_path(const std::string& name) {
  return ::rsu::lidar::test::real_data_path("ouster/" + name);
}

Metadata load(const std::string& name) {
  return parse_metadata(io::read_text_file(data_path(name)), name);
}

std::string real_text(const std::string& name) {
  return io::read_text_file(data_path(name));
}

// The error parse_metadata throws for `text`, or "" if it parsed.
std::string error_of(const std::string& text) {
  try {
    parse_metadata(text, "m.json");
  } catch (const io::YamlError& e) {
    return e.what();
  }
  return "";
}

// `text` with the first occurrence of `from` replaced by `to` (the test fails if it is absent).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

// JSON with every space and newline outside strings removed (as a sensor's HTTP API sends it).
std::string compact(const std::string& json) {
  std::string out;
  bool in_string = false;
  for (const char c : json) {
    if (c == '"') {
      in_string = !in_string;
    }
    if (in_string || (c != ' ' && c != '\n' && c != '\r' && c != '\t')) {
      out += c;
    }
  }
  return out;
}

TEST(OusterMetadata, Os1_32LegacyFlatFile) {
  const Metadata m = load("OS-1-32-G_v2.1.1_1024x10.json");
  EXPECT_EQ(m.layout, MetadataLayout::flat);
  EXPECT_EQ(m.prod_line, "OS-1-32-G");
  EXPECT_EQ(m.model_name(), "os1-32");
  EXPECT_EQ(m.serial, "992101000280");
  EXPECT_EQ(m.serial_number, 992101000280ULL);
  EXPECT_FALSE(m.initialization_id.has_value());
  EXPECT_EQ(m.firmware, "v2.1.1");
  EXPECT_EQ(m.lidar_mode, "1024x10");
  EXPECT_EQ(m.columns_per_frame, 1024);
  EXPECT_EQ(m.frequency_hz, 10);
  EXPECT_EQ(m.columns_per_packet, 16);
  EXPECT_EQ(m.pixels_per_column, 32);
  EXPECT_EQ(m.column_window_first, 0);
  EXPECT_EQ(m.column_window_last, 1023);
  EXPECT_EQ(m.columns_in_window(), 1024);
  EXPECT_EQ(m.profile, UdpProfile::legacy);  // firmware 2.1 files name no profile: LEGACY
  ASSERT_EQ(m.beam_altitude_deg.size(), 32U);
  EXPECT_DOUBLE_EQ(m.beam_altitude_deg.front(), 12.75);
  EXPECT_DOUBLE_EQ(m.beam_altitude_deg.back(), -15.32);
  EXPECT_DOUBLE_EQ(m.beam_azimuth_deg.front(), -4.22);
  EXPECT_DOUBLE_EQ(m.beam_azimuth_deg[8], 4.27);
  EXPECT_DOUBLE_EQ(m.beam_origin_x_mm, 15.806);
  EXPECT_DOUBLE_EQ(m.beam_origin_z_mm, 0.0);
  EXPECT_DOUBLE_EQ(m.lidar_to_sensor(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(m.lidar_to_sensor(1, 1), -1.0);
  EXPECT_DOUBLE_EQ(m.lidar_to_sensor(2, 2), 1.0);
  EXPECT_DOUBLE_EQ(m.lidar_to_sensor(2, 3), 36.18);
  EXPECT_EQ(m.udp_port_lidar, 7502);  // not in the file: defaults, listed
  EXPECT_EQ(m.udp_port_imu, 7503);
  EXPECT_EQ(m.defaults_used.size(), 3U);  // profile and both ports
}

TEST(OusterMetadata, Os1_128LowBandwidthFile) {
  const Metadata m = load("OS-1-128_v2.3.0_1024x10.json");
  EXPECT_EQ(m.layout, MetadataLayout::flat);
  EXPECT_EQ(m.model_name(), "os1-128");
  EXPECT_EQ(m.profile, UdpProfile::rng15_rfl8_nir8);
  EXPECT_EQ(m.pixels_per_column, 128);
  EXPECT_EQ(m.serial_number, 122201000998ULL);
  EXPECT_EQ(m.initialization_id, 7109750U);
  EXPECT_EQ(m.udp_port_lidar, 7502);
  EXPECT_EQ(m.udp_port_imu, 7503);
  EXPECT_TRUE(m.defaults_used.empty());
  EXPECT_DOUBLE_EQ(m.beam_altitude_deg.front(), 20.95);
  EXPECT_DOUBLE_EQ(m.beam_altitude_deg.back(), -21.82);
}

TEST(OusterMetadata, OtherRealFiles) {
  const Metadata os2_32 = load("OS-2-32-U0_v2.0.0_1024x10.json");  // named 1024x10, set to 1024x20
  EXPECT_EQ(os2_32.lidar_mode, "1024x20");
  EXPECT_EQ(os2_32.frequency_hz, 20);
  EXPECT_EQ(os2_32.model_name(), "os2-32");
  EXPECT_DOUBLE_EQ(os2_32.beam_origin_x_mm, 13.762);
  const Metadata os2_128 = load("OS-2-128-U1_v2.3.0_1024x10.json");
  EXPECT_EQ(os2_128.profile, UdpProfile::rng19_rfl8_sig16_nir16);
  EXPECT_EQ(os2_128.model_name(), "os2-128");
  const Metadata os0 = load("OS-0-128-U1_v2.3.0_1024x10.json");
  EXPECT_EQ(os0.profile, UdpProfile::rng15_rfl8_nir8);
  EXPECT_EQ(os0.model_name(), "os0-128");
}

// The SDK's files of one sensor (firmware 2.5.0) in both layouts: one geometry and format.
TEST(OusterMetadata, NestedAndFlatLayoutsOfOneSensorAgree) {
  const Metadata nested = load("2_5_0_os-992146000760-128.json");
  const Metadata flat = load("2_5_0_os-992146000760-128_legacy.json");
  EXPECT_EQ(nested.layout, MetadataLayout::nested);
  EXPECT_EQ(flat.layout, MetadataLayout::flat);
  EXPECT_EQ(nested.prod_line, "OS-1-128");
  EXPECT_EQ(nested.serial_number, 992146000760ULL);
  EXPECT_EQ(nested.initialization_id, 8247301U);
  EXPECT_EQ(nested.profile, UdpProfile::rng19_rfl8_sig16_nir16);
  EXPECT_EQ(nested.column_window_first, 912);  // an azimuth window
  EXPECT_EQ(nested.column_window_last, 1022);
  EXPECT_EQ(nested.columns_in_window(), 111);
  EXPECT_TRUE(nested.in_window(912));
  EXPECT_FALSE(nested.in_window(1023));
  for (const Metadata* m : {&nested, &flat}) {
    SCOPED_TRACE(m == &nested ? "nested" : "flat");
    EXPECT_EQ(m->serial_number, nested.serial_number);
    EXPECT_EQ(m->initialization_id, nested.initialization_id);
    EXPECT_EQ(m->lidar_mode, nested.lidar_mode);
    EXPECT_EQ(m->columns_per_packet, nested.columns_per_packet);
    EXPECT_EQ(m->pixels_per_column, nested.pixels_per_column);
    EXPECT_EQ(m->column_window_first, nested.column_window_first);
    EXPECT_EQ(m->column_window_last, nested.column_window_last);
    EXPECT_EQ(m->profile, nested.profile);
    EXPECT_EQ(m->beam_altitude_deg, nested.beam_altitude_deg);
    EXPECT_EQ(m->beam_azimuth_deg, nested.beam_azimuth_deg);
    EXPECT_DOUBLE_EQ(m->beam_origin_x_mm, 15.806);
    EXPECT_EQ(m->lidar_to_sensor, nested.lidar_to_sensor);
    EXPECT_EQ(m->udp_port_lidar, nested.udp_port_lidar);
  }
}

TEST(OusterMetadata, CompactJsonParsesTheSame) {
  const std::string name = "2_5_0_os-992146000760-128.json";
  const Metadata spaced = load(name);
  const Metadata packed = parse_metadata(compact(real_text(name)), name);
  EXPECT_EQ(packed.beam_altitude_deg, spaced.beam_altitude_deg);
  EXPECT_EQ(packed.profile, spaced.profile);
  EXPECT_EQ(packed.column_window_first, spaced.column_window_first);
}

// Firmware 1.x files have no data format and no beam origin: the SDK's defaults, listed.
TEST(OusterMetadata, OldFirmwareDefaults) {
  std::string text = real_text("OS-1-32-G_v2.1.1_1024x10.json");
  const std::size_t df = text.find("\"data_format\"");
  const std::size_t df_end = text.find("},", df);
  ASSERT_NE(df, std::string::npos);
  text.erase(df, df_end + 2 - df);
  text = replaced(text, "\"lidar_origin_to_beam_origin_mm\": 15.806,", "");
  text = replaced(
      text, "\"lidar_to_sensor_transform\": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1],", "");
  const Metadata m = parse_metadata(text, "old.json");
  EXPECT_EQ(m.columns_per_frame, 1024);
  EXPECT_EQ(m.columns_per_packet, 16);
  EXPECT_EQ(m.pixels_per_column, 32);
  EXPECT_EQ(m.columns_in_window(), 1024);
  EXPECT_DOUBLE_EQ(m.beam_origin_x_mm, 15.806);  // OS-1 default
  EXPECT_DOUBLE_EQ(m.lidar_to_sensor(2, 3), 36.18);
  EXPECT_EQ(m.defaults_used.size(), 5U);
}

TEST(OusterMetadata, ErrorsNameTheFileLineAndField) {
  const std::string os1 = real_text("OS-1-32-G_v2.1.1_1024x10.json");
  const std::string nested = real_text("2_5_0_os-992146000760-128.json");
  struct Case {
    std::string text;
    std::string expected;  // a part of the error message
  };
  const std::vector<Case> cases = {
      {"", "m.json:1: <document>: expected a JSON object"},
      {"[1, 2]", "expected a JSON object"},
      {"{\"a\": 1}", "not an Ouster metadata file"},
      {"{\"beam_altitude_angles\": [1, ", "m.json:1: <syntax>"},
      {replaced(os1, "\"lidar_mode\": \"1024x10\",", ""),
       "<document>: missing required field \"lidar_mode\""},
      {replaced(os1, "\"1024x10\"", "\"1024x15\""), "m.json:19: lidar_mode: unknown lidar_mode \"1024x15\""},
      {replaced(os1, "\"columns_per_frame\": 1024", "\"columns_per_frame\": 2048"),
       "m.json:11: data_format.columns_per_frame: contradicts lidar_mode 1024x10"},
      {replaced(os1, "\"pixels_per_column\": 32", "\"pixels_per_column\": 33"),
       "data_format.pixels_per_column: expected 16, 32"},
      {replaced(os1, "\"columns_per_packet\": 16", "\"columns_per_packet\": 15"),
       "columns_per_packet: must divide"},
      {replaced(os1, "\"columns_per_packet\": 16", "\"columns_per_packet\": 512"),
       "columns_per_packet: a lidar packet"},
      {replaced(os1, "[12.75, ", "[\"high\", "),
       "m.json:4: beam_altitude_angles[0]: expected a number, got \"high\""},
      {replaced(os1, "[12.75, ", "["), "m.json:4: beam_altitude_angles: expected 32 numbers, got 31"},
      {replaced(os1, "[12.75, ", "[95, "), "beam_altitude_angles[0]: expected a value within"},
      {replaced(os1, "\"column_window\": [0, 1023]", "\"column_window\": [0, 1024]"),
       "data_format.column_window[1]: expected an integer in [0, 1023]"},
      {replaced(os1, "[-1, 0, 0, 0, 0, -1, 0, 0,", "[-1, 0, 0, 0, 0, -2, 0, 0,"),
       "lidar_to_sensor_transform: expected a rigid transform"},
      {replaced(os1, "\"pixels_per_column\": 32",
                "\"pixels_per_column\": 32, \"udp_profile_lidar\": \"RNG19_RFL8_SIG16_NIR16_DUAL\""),
       "data_format.udp_profile_lidar: unsupported lidar profile \"RNG19_RFL8_SIG16_NIR16_DUAL\""},
      {replaced(os1, "{", "{\"beam_intrinsics\": {},"), "both the flat layout"},
      {replaced(nested, "\"lidar_mode\": \"1024x10\",", ""),
       "config_params: missing required field \"lidar_mode\""},
      {replaced(nested, "\"beam_azimuth_angles\": \n        [", "\"beam_azimuth_angles\": [1, "),
       "beam_intrinsics.beam_azimuth_angles: expected 128 numbers, got 129"},
      {replaced(nested, "\"initialization_id\": 8247301", "\"initialization_id\": -1"),
       "sensor_info.initialization_id: expected an integer"},
      {replaced(nested, "\"udp_port_lidar\": 7502", "\"udp_port_lidar\": 70000"),
       "config_params.udp_port_lidar"},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(c.text);
    EXPECT_NE(error.find(c.expected), std::string::npos) << "expected \"" << c.expected << "\" in: " << error;
  }
}

TEST(OusterMetadata, ProfileNamesRoundTrip) {
  for (const UdpProfile p :
       {UdpProfile::legacy, UdpProfile::rng19_rfl8_sig16_nir16, UdpProfile::rng15_rfl8_nir8}) {
    EXPECT_EQ(udp_profile_from_string(to_string(p)), p);
  }
  EXPECT_FALSE(udp_profile_from_string("FIVE_WORD_PIXEL").has_value());
}

TEST(OusterMetadata, SensorModelForTheRestOfThePipeline) {
  const Metadata m = load("OS-1-128_v2.3.0_1024x10.json");
  const SensorModel s = sensor_model(m, 0.5);
  EXPECT_EQ(sensor_model_error(s), "");
  EXPECT_EQ(s.name, "os1-128");
  EXPECT_EQ(s.laser_count(), 128U);
  EXPECT_DOUBLE_EQ(s.rotation_hz(), 10.0);
  EXPECT_NEAR(s.sequence_period_us, 97.65625, 1e-9);  // one column: 1 / (10 Hz x 1024)
  EXPECT_NEAR(s.sequences_per_rotation(), 1024.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.elevation_deg[5], m.beam_altitude_deg[5]);
  EXPECT_DOUBLE_EQ(s.azimuth_offset_deg[5], m.beam_azimuth_deg[5]);
  EXPECT_DOUBLE_EQ(s.distance_unit_m, 0.008);
  EXPECT_FALSE(s.has_packet_format());
}

}  // namespace
}  // namespace rsu::lidar::ouster
